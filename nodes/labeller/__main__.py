"""``python -m counterpart.nodes.labeller --param use_tracker=false ...``: run the labeller node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.labeller.node:Labeller"))
