"""``python -m nodes.calibration --param file=camera.yaml``: run the calibration node alone."""
import sys

from bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("nodes.calibration.node:Calibration"))
