"""``python -m counterpart.nodes.camera --param source=clip.avi ...``: run the camera node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.camera.node:Camera"))
