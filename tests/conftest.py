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


@pytest.fixture(scope="session")
def models_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model cache (``COUNTERPART_MODELS``) of small responder models trained in seconds on planted
    interactions: a dual HMM, an emotion model whose angry style doubles the amplitude at full
    strength, and a listener that nods back at a nod.
    """
    import numpy as np

    from counterpart.nodes.responder.dual_hmm import DualHMM, DualHMMConfig, FitConfig
    from counterpart.nodes.responder.emotion import EmotionModel
    from counterpart.nodes.responder.listener import ListenerModel
    from counterpart.nodes.responder.models import save_model
    from tests.responder_fixtures import planted_pair

    d = tmp_path_factory.mktemp("models")
    save_model(
        d / "responder-dual-hmm.npz",
        DualHMM(DualHMMConfig(fit=FitConfig(n_states=8, n_iter=10, both_roles=False))).fit(
            [planted_pair(s) for s in range(6)]
        ),
    )
    em = EmotionModel().fit(
        np.random.default_rng(0).normal(size=(8, 7)), ["neutral", "angry"] * 4, [0, 1] * 4, ["g"] * 8
    )
    em.k_amp_[:] = np.log(2.0)
    em.k_speed_[:] = np.log(2.0)
    save_model(d / "responder-emotion.npz", em)
    save_model(d / "responder-listener.npz", ListenerModel().fit({"interested": [(("S:nod",), ("L:nod",), 0.9)]}))
    return d


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
