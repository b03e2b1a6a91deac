"""The model's own frames within each input frame's interval (``ModelClock``) and the observed
joints interpolated to them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from counterpart.nodes.responder.model_clock import AtModelRate, ModelClock, interpolated


@pytest.mark.parametrize("input_fps", [25.0, 30.0, 15.0, 60.0, 29.97])
def test_the_model_steps_at_its_own_rate_for_input_at_any(input_fps: float) -> None:
    clock = ModelClock(25.0)
    n = int(input_fps * 4)  # four seconds of input
    fractions = [clock.advance(1 / input_fps) for _ in range(n + 1)]
    assert np.array_equal(fractions[0], [1.0])  # the first input steps at once
    # the model's frames fall at its own times: k / 25 s, each once
    times = np.concatenate([(i - 1 + f) / input_fps for i, f in enumerate(fractions[1:], 1)])
    np.testing.assert_allclose(times, np.arange(1, len(times) + 1) / 25.0, atol=1e-9)
    assert len(times) == 100 - (input_fps == 29.97)
    assert all(np.all((f > 0) & (f <= 1)) for f in fractions)
    if input_fps == 25.0:
        assert all(np.array_equal(f, [1.0]) for f in fractions)


def test_a_long_interval_steps_the_model_at_most_max_steps_times_and_keeps_its_phase() -> None:
    clock = ModelClock(25.0, max_steps=3)
    clock.advance(0.0)
    # 12.5 model frames: the last three of the twelve, and the half frame left carried on
    np.testing.assert_allclose(clock.advance(0.5), [10 / 12.5, 11 / 12.5, 12 / 12.5])
    np.testing.assert_allclose(clock.advance(0.02), [1.0])
    np.testing.assert_allclose(clock.advance(0.02), [])
    clock.reset()
    np.testing.assert_allclose(clock.advance(5.0), [1.0])
    with pytest.raises(ValueError, match="fps"):
        ModelClock(0.0)


def test_the_observed_joints_are_interpolated_to_the_models_frames() -> None:
    prev, cur = np.zeros((14, 3)), np.ones((14, 3))
    x = interpolated(prev, cur, np.array([0.25, 1.0]))
    assert x.shape == (2, 14, 3)
    np.testing.assert_allclose(x[:, 0, 0], [0.25, 1.0])
    np.testing.assert_allclose(interpolated(None, cur, np.array([0.5])), cur[None])  # nothing before: held


def test_a_model_at_25_fps_fed_at_50_steps_on_every_other_input_on_its_own_frames_joints() -> None:
    seen: list[np.ndarray] = []

    def step(x: np.ndarray | None) -> int:
        seen.append(x)
        return len(seen)

    rate = AtModelRate(ModelClock(25.0))
    X = np.arange(10, dtype=float)[:, None, None] * np.ones((10, 14, 3))
    out = [rate(step, X[i], i / 50.0) for i in range(10)]
    assert out == [1, 1, 2, 2, 3, 3, 4, 4, 5, 5]  # the last output holds where no model frame fell
    np.testing.assert_allclose([x[0, 0] for x in seen], [0, 2, 4, 6, 8])
    assert rate(step, X[0], 0.0) == 6  # time going back: afresh, one step at once


def test_counterpart_respond_steps_the_model_on_its_own_frames_for_a_file_at_another_rate() -> None:
    # a listener (25 fps) answers a nod at 1 s: the file at 50 fps gives, on the frames the two
    # share, the partner the file at 25 fps gives (stepped once per frame it nodded at 1.2 s)
    from counterpart.apps.respond import generate
    from counterpart.nodes.responder.listener import ListenerModel
    from tests.responder_fixtures import planted_pair

    pair = planted_pair(7, T=75)
    nod = ((np.arange(75) >= 25) & (np.arange(75) < 37)).astype(np.int8)[:, None]
    at25 = replace(pair, signals_a=nod, signals_b=np.zeros_like(nod), signal_names=("nod",))
    at50 = at25.resample(50.0)
    model = ListenerModel().fit({"interested": [(("S:nod",), ("L:nod",), 0.9)]})
    out25, out50 = generate(model, at25), generate(model, at50)
    assert out25.shape == (75, 14, 3) and out50.shape == (149, 14, 3)
    np.testing.assert_allclose(out50[::2], out25, atol=1e-5)
    assert np.abs(out25[36] - out25[34]).max() > 0.01  # the head nods from frame 35 (1.4 s)
