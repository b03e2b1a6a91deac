"""``python -m counterpart.nodes.calibration --param file=camera.yaml``: run the calibration node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.calibration.node:Calibration"))
