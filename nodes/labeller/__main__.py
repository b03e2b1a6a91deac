"""``python -m nodes.labeller --param use_tracker=false ...``: run the labeller node alone."""
import sys

from bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("nodes.labeller.node:Labeller"))
