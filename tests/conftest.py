"""Fixtures shared by the test modules."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def demo_models(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One model cache (``COUNTERPART_MODELS``) for every ``counterpart demo`` of the session: the
    first demo trains the default models into it (a minute or more on two cores), the later ones
    load them.
    """
    return tmp_path_factory.mktemp("demo-models")
