"""Where the third-party data of ``../shared/data`` lives; tests that need it skip when it is absent.
``COUNTERPART_SHARED_DATA`` points elsewhere.
"""

from __future__ import annotations

import os
from pathlib import Path

DATA = Path(os.environ.get("COUNTERPART_SHARED_DATA") or Path(__file__).resolve().parents[2] / "shared" / "data")
VTEST = DATA / "video" / "vtest.avi"
CMU = DATA / "cmu"
