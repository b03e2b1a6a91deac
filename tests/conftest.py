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


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels() -> None:
    """The numba kernels (the silhouette models', the tracker's likelihood) compiled into their
    cache once, before the first test: on a fresh install the first node process to need them would
    otherwise compile them for several seconds inside whichever graph test comes first. Where they
    are not cached yet, the parts are compiled side by side, one process each, as the demo does.
    """
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    from counterpart.apps.kernel_cache import COMPILE_PARTS, compile_kernels, kernels_cached

    if kernels_cached():
        compile_kernels()  # only loads them
        return
    with ProcessPoolExecutor(COMPILE_PARTS, mp_context=get_context("spawn")) as pool:
        for done in [pool.submit(compile_kernels, part, COMPILE_PARTS) for part in range(COMPILE_PARTS)]:
            done.result()
