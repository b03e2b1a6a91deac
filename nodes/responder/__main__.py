"""``python -m counterpart.nodes.responder --param model=dual-hmm ...``: run the responder node alone."""

import sys

from counterpart.bus.runner import run_standalone

if __name__ == "__main__":
    sys.exit(run_standalone("counterpart.nodes.responder.node:Responder"))
