"""``python -m nodes.silhouette --param backend=mog2 ...``: run the silhouette node alone."""
import sys

from bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("nodes.silhouette.node:Silhouette"))
