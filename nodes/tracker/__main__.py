"""``python -m counterpart.nodes.tracker --param people='[left]' ...``: run the tracker node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.tracker.node:TrackerNode"))
