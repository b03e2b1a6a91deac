"""``python -m nodes.tracker --param people='[left]' ...``: run the tracker node alone."""
import sys

from bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("nodes.tracker.node:TrackerNode"))
