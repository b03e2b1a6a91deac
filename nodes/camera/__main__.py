"""``python -m nodes.camera --param source=clip.avi ...``: run the camera node alone."""
import sys

from bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("nodes.camera.node:Camera"))
