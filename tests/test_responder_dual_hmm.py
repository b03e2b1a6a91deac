"""The dual HMM learns a planted interaction and reproduces the partner from the observed person."""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.nodes.responder.dual_hmm import DualHMM, DualHMMConfig, FitConfig
from counterpart.nodes.responder.frames import actor_frame, relative_pair, to_world
from counterpart.nodes.responder.models import MODEL_VERSION, ModelVersionError, load_model, save_model
from tests.responder_fixtures import mpjpe_mm, planted_pair


@pytest.fixture(scope="module")
def model() -> DualHMM:
    return DualHMM(DualHMMConfig(fit=FitConfig(n_states=12, n_iter=15, both_roles=False))).fit(
        [planted_pair(s) for s in range(8)]
    )


def test_actor_frame_round_trip_and_facing() -> None:
    tr = planted_pair(3)
    o, th = actor_frame(tr.a)
    la, lb = relative_pair(tr.a, tr.b)
    assert np.allclose(to_world(la, o, th), tr.a, atol=1e-5)
    # B stands 1.3 m straight ahead of A (+Z local), whatever the world heading
    mid_b = 0.5 * (lb[:, 8] + lb[:, 11])
    assert np.allclose(mid_b[:, [0, 2]], [[0.0, 1.3]], atol=0.03)


def test_reproduces_planted_partner_at_new_places(model: DualHMM) -> None:
    test = planted_pair(100)
    pred = model.predict(test.a)
    assert pred.shape == test.b.shape and pred.dtype == np.float32
    err = mpjpe_mm(pred, test.b)
    # baseline: the partner's mean pose, placed in A's frame (what a model without the observed gives)
    _, lb = relative_pair(
        np.concatenate([planted_pair(s).a for s in range(8)]), np.concatenate([planted_pair(s).b for s in range(8)])
    )
    o, th = actor_frame(test.a)
    base = mpjpe_mm(to_world(np.broadcast_to(lb.mean(0), test.b.shape), o, th), test.b)
    assert err < 0.35 * base, (err, base)
    assert err < 40.0
    # the answering left wrist follows A's raised right wrist in height
    assert np.corrcoef(pred[:, 4, 1], test.a[:, 7, 1])[0, 1] > 0.9


def test_viterbi_trellis_decoding_is_also_faithful(model: DualHMM) -> None:
    test = planted_pair(101)
    arrays, config = model.get_state()
    vit = DualHMM.from_state(arrays, {**config, "decode": "viterbi", "lag": 6})
    assert mpjpe_mm(vit.predict(test.a), test.b) < 60.0


def test_placement_correction_forest_arrays_predict_as_scikit_learn() -> None:
    from sklearn.ensemble import ExtraTreesRegressor

    from counterpart.nodes.responder.placement_correction import ForestArrays

    rng = np.random.default_rng(0)
    X = rng.normal(size=(2000, 5))
    Y = np.c_[np.sin(X[:, 0]) + X[:, 1] ** 2, X[:, 2] * (X[:, 3] > 0)]
    et = ExtraTreesRegressor(7, min_samples_leaf=5, random_state=0).fit(X, Y)
    forest = ForestArrays.from_sklearn(et)
    Xt = rng.normal(size=(50, 5))
    assert np.allclose(np.stack([forest.predict(x) for x in Xt]), et.predict(Xt), atol=1e-9)


def test_model_file_round_trip_and_version_error(model: DualHMM, tmp_path) -> None:
    path = save_model(tmp_path / "m.npz", model, {"sequences": 8})
    # the cross-fitted placement correction travels in the file
    assert model.forest_ is not None and "correction_value" in np.load(path).files
    back = load_model(path, expected="dual-hmm")
    test = planted_pair(102)
    assert np.allclose(back.predict(test.a), model.predict(test.a), atol=1e-5)
    # rewrite the metadata with another version: loading names the file and both versions
    import json

    z = dict(np.load(path))
    meta = json.loads(str(z.pop("__meta__")))
    meta["version"] = 99
    np.savez(tmp_path / "old.npz", __meta__=np.array(json.dumps(meta)), **z)
    with pytest.raises(ModelVersionError, match=rf"old\.npz.*version 99.*reads version {MODEL_VERSION}"):
        load_model(tmp_path / "old.npz")
    with pytest.raises(ValueError, match="holds a 'dual-hmm' model, expected 'listener'"):
        load_model(path, expected="listener")


def test_phased_trajectories_get_time_ordered_states() -> None:
    from hmmlearn.hmm import GaussianHMM

    from counterpart.nodes.responder.hmm_blocks import init_ordered

    # the ordered start: states shared out between the phases by frames, along time within each
    rng = np.random.default_rng(0)
    seqs, phases = [], []
    for T in (60, 90, 75):
        t = np.linspace(0, 1, T)
        seqs.append(np.stack([t, rng.normal(0, 0.01, T)], axis=1))
        phases.append((t >= 0.25).astype(np.int32))
    hmm = GaussianHMM(n_components=4, covariance_type="full", init_params="")
    init_ordered(hmm, seqs, phases, order_mix=0.2, min_covar=1e-2)
    assert np.all(np.diff(hmm.means_[:, 0]) > 0)  # state k: the k-th stretch of time
    assert hmm.means_[0, 0] < 0.25 <= hmm.means_[1, 0]  # one state for the first phase's quarter
    assert np.argmax(hmm.startprob_) == 0
    assert np.allclose(hmm.transmat_.sum(1), 1) and hmm.transmat_[0, 2] < hmm.transmat_[0, 1]
    # phased trajectories fit and still reproduce the partner
    data = [planted_pair(s) for s in range(6)]
    for tr in data:
        tr.phase = (np.arange(tr.n_frames) >= tr.n_frames // 3).astype(np.int32)
    m = DualHMM(DualHMMConfig(fit=FitConfig(n_states=6, n_iter=10, both_roles=False))).fit(data)
    test = planted_pair(100)
    assert mpjpe_mm(m.predict(test.a), test.b) < 60.0
    with pytest.raises(ValueError, match="order_mix"):
        FitConfig(order_mix=1.5)


def test_the_grouped_config_reads_and_writes_the_model_files_flat_names() -> None:
    from counterpart.nodes.responder.dual_hmm import CorrectionConfig, DecodeConfig, PlacementConfig

    # the names of model format version 4: files written before the grouping load unchanged
    flat = DualHMMConfig().flat()
    assert list(flat) == [
        "n_states", "energy", "velocity_weight", "n_iter", "decode", "lag", "placement", "process_noise",
        "evidence_weight", "leak", "both_roles", "order_mix", "min_covar", "random_state",
        "correction_folds", "correction_trees", "correction_leaf",
    ]  # fmt: skip
    cfg = DualHMMConfig(
        fit=FitConfig(n_states=7, leak=0.01),
        decode=DecodeConfig(decode="viterbi", lag=3),
        placement=PlacementConfig(mode="relative"),
        correction=CorrectionConfig(folds=0),
    )
    assert DualHMMConfig.from_flat(cfg.flat()) == cfg
    assert DualHMMConfig.from_flat({"n_states": 7}).fit.n_states == 7
    with pytest.raises(ValueError, match=r"unknown dual-hmm setting\(s\) \['states'\]"):
        DualHMMConfig.from_flat({"states": 7})
    with pytest.raises(ValueError, match="placement='nearby'"):
        DualHMMConfig.from_flat({"placement": "nearby"})
    with pytest.raises(TypeError, match="expected a DualHMMConfig"):
        DualHMM(12)  # type: ignore[arg-type]
