"""``python -m counterpart.nodes.renderer --param video=out.mp4 ...``: run the renderer node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.renderer.node:Renderer"))
