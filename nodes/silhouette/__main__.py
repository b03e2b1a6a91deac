"""``python -m counterpart.nodes.silhouette --param backend=mog2 ...``: run the silhouette node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.silhouette.node:Silhouette"))
