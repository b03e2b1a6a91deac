"""Annealed particle filter (Deutscher, Blake & Reid 2000) and a plain particle filter.

One frame of the annealed filter (paper sect. 4, with the adaptive schedule of sect. 5)::

    particles <- predict_fn(particles of the last frame)           dynamics / motion prior
    for layer m = 1..M:
        l_i   = log w(Z, x_i)                                       observation model
        beta_m: the exponent whose weights pi_i ~ exp(beta_m l_i) give the survival rate
                D = 1 / (N sum pi_i^2) = alpha      (eq. 11, solved by a bracketing search on log beta)
        estimate (last layer): weighted mean of the particles, best particle, ESS = N D
        resample N particles by pi (systematic)
        diffuse (not after the last layer): Gaussian noise per DOF, std = ``diffusion`` x the
                spread of the resampled set, clipped to [min_std, max_std], x ``shrink``^m;
                clip_to_limits

With the diffusion proportional to the set's spread (Deutscher & Reid 2005), the search narrows by
itself along the DOFs the observation pins down and stays broad along those it cannot see (depth
and heading from one camera), so the weighted mean averages over them instead of following noise.

Angles in radians, positions in metres (``counterpart.body.pose``). The yaw is averaged on the circle.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from counterpart.body.pose import DOF, YAW, clip_to_limits, wrap_angle

LogLikelihood = Callable[[np.ndarray], np.ndarray]
PredictFn = Callable[[np.ndarray, np.random.Generator], np.ndarray]

#: lower bound of the per-DOF diffusion std: 5 mm for positions, about 0.6 degree for angles
MIN_STD = np.where(np.arange(DOF) < 3, 0.005, 0.01)


@dataclass
class Estimate:
    """Result of one filter step.

    Attributes
    ----------
    mean : ndarray of shape (DOF,)
        Weighted mean pose of the last layer (yaw: circular mean).
    best : ndarray of shape (DOF,)
        Highest-likelihood particle of the last layer.
    ess : float
        Effective sample size 1 / sum(pi^2) of the last layer's particles weighted by the
        un-annealed log-likelihood (beta = 1), before resampling: between 1 (one particle holds
        all the posterior mass) and N.
    log_likelihood : float
        Log-likelihood of the best particle.
    particles : ndarray of shape (N, DOF)
        The resampled set carried to the next frame.
    betas : ndarray of shape (M,)
        Chosen exponents per layer.
    survival : ndarray of shape (M,)
        Achieved survival rates D per layer.
    n_evals : int
        Likelihood evaluations spent on this frame.
    """

    mean: np.ndarray
    best: np.ndarray
    ess: float
    log_likelihood: float
    particles: np.ndarray
    betas: np.ndarray = field(default_factory=lambda: np.zeros(0))
    survival: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n_evals: int = 0


def run_steps(steps: Generator[np.ndarray, np.ndarray, Estimate], log_likelihood: LogLikelihood) -> Estimate:
    """Drive a filter's :meth:`~AnnealedParticleFilter.steps` with a likelihood.

    Parameters
    ----------
    steps : generator
        The search (yields particles, is sent their log-likelihoods, returns the Estimate).
    log_likelihood : callable
        (N, DOF) poses -> (N,) log-likelihoods.

    Returns
    -------
    Estimate
        The search's estimate.
    """
    try:
        P = next(steps)
        while True:
            P = steps.send(log_likelihood(P))
    except StopIteration as stop:
        return stop.value


def _normalised(ll: np.ndarray, beta: float) -> np.ndarray:
    a = beta * (ll - ll.max())
    w = np.exp(a)
    return w / w.sum()


def survival_rate(ll: np.ndarray, beta: float) -> float:
    """D = 1 / (N sum pi^2) of weights pi ~ exp(beta * ll) (Deutscher eq. 11).

    Parameters
    ----------
    ll : ndarray of shape (N,)
        Log-likelihoods of the particles.
    beta : float
        The annealing exponent.

    Returns
    -------
    float
        The survival rate D, in [1/N, 1].
    """
    w = _normalised(ll, beta)
    return float(1.0 / (len(ll) * np.dot(w, w)))


def choose_beta(
    ll: np.ndarray, survival: float, lo: float = 1e-3, hi: float = 1e6, grid: int = 24, refine: tuple[int, ...] = (8, 8)
) -> float:
    """The exponent beta whose weights exp(beta * ll) have survival rate ``survival``.

    D(beta) falls monotonically from 1 (beta = 0) towards 1/N, so a bracketing search on log beta
    finds it. The first round evaluates log(N D) at ``grid`` points of the whole bracket at once
    (one (grid, N) array), and each round of ``refine`` at that many points of the cell where it
    crosses log(N survival); the last cell is closed by linear interpolation of log D in log beta,
    which is smooth there. The defaults pin log beta about as finely as 5 rounds of 16 points
    without interpolation (``tests/test_tracker_algorithm.py`` holds them to a bisection), in 3
    array evaluations instead of 7: at the few dozen particles of a real-time frame the cost of
    this function is its numpy calls, not their arithmetic.

    Parameters
    ----------
    ll : ndarray of shape (N,)
        Log-likelihoods of the particles.
    survival : float
        Target survival rate, in (0, 1).
    lo, hi : float, default=1e-3, 1e6
        Bracket of beta; ``lo`` is returned when even it survives too few, ``hi`` when even it
        survives too many.
    grid : int, default=24
        Points of the whole bracket evaluated in the first round (at least 2).
    refine : tuple of int, default=(8, 8)
        Points evaluated in each further round, across the cell the previous one found (each at
        least 2).

    Returns
    -------
    float
        beta. When the log-likelihoods are all equal every beta gives D = 1 and ``hi`` is returned.

    Raises
    ------
    ValueError
        If ``survival`` is not in (0, 1).
    """
    if not 0 < survival < 1:
        raise ValueError(f"survival={survival!r}: the target survival rate must lie in (0, 1)")
    ll = np.asarray(ll, dtype=np.float64)
    top = ll.max()
    spread = float(top - ll.min())
    if not np.isfinite(spread) or spread <= 0:
        return hi
    d = ll - top
    target = np.log(survival * len(d))
    logb, betas = _bracket_grid(lo, hi, grid)
    for r in range(len(refine) + 1):
        w = np.exp(np.multiply.outer(betas, d))  # (points, N)
        s1 = w.sum(axis=1)
        w *= w
        g = 2.0 * np.log(s1) - np.log(w.sum(axis=1))  # log(N D) = log(S1^2 / S2), falling in beta
        if r == 0:
            if g[0] <= target:  # even lo survives too few
                return lo
            if g[-1] >= target:  # even hi survives too many
                return hi
        k = min(max(int(np.searchsorted(-g, -target)), 1), len(g) - 1)  # g[k-1] > target >= g[k]
        a, b, ga, gb = logb[k - 1], logb[k], g[k - 1], g[k]
        if r < len(refine):
            logb = a + (b - a) * _unit_steps(refine[r])
            betas = np.exp(logb)
    f = (ga - target) / (ga - gb) if ga > gb else 0.5
    return float(np.exp(a + f * (b - a)))


@lru_cache(maxsize=4)
def _bracket_grid(lo: float, hi: float, grid: int) -> tuple[np.ndarray, np.ndarray]:
    """``choose_beta``'s first grid over the whole bracket [lo, hi]: log beta and beta, read-only."""
    logb = np.log(lo) + (np.log(hi) - np.log(lo)) * _unit_steps(grid)
    betas = np.exp(logb)
    logb.flags.writeable = betas.flags.writeable = False
    return logb, betas


@lru_cache(maxsize=8)
def _unit_steps(n: int) -> np.ndarray:
    """The n points evenly from 0 to 1, read-only (a grid across a bracket before scaling)."""
    if n < 2:
        raise ValueError(f"choose_beta: {n} grid point(s); a round needs at least 2")
    out = np.linspace(0.0, 1.0, n)
    out.flags.writeable = False
    return out


def systematic_resample(w: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Systematic resampling (one uniform draw).

    Parameters
    ----------
    w : ndarray of shape (N,)
        Normalised weights.
    rng : numpy.random.Generator
        Source of the uniform draw.

    Returns
    -------
    ndarray of shape (N,)
        Indices of the resampled particles.
    """
    N = len(w)
    positions = (rng.random() + np.arange(N)) / N
    idx = np.searchsorted(np.cumsum(w), positions)
    return np.minimum(idx, N - 1)


def weighted_mean_pose(P: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted mean with the yaw averaged on the circle.

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    w : ndarray of shape (N,)
        Normalised weights.

    Returns
    -------
    ndarray of shape (DOF,)
        The mean pose.
    """
    m = w @ P
    m[YAW] = np.arctan2(w @ np.sin(P[:, YAW]), w @ np.cos(P[:, YAW]))
    return m


def weighted_std(P: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted standard deviation per DOF (yaw on the circle).

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    w : ndarray of shape (N,)
        Normalised weights.

    Returns
    -------
    ndarray of shape (DOF,)
        Standard deviations, metres / radians.
    """
    m = weighted_mean_pose(P, w)
    d = P - m
    d[:, YAW] = wrap_angle(d[:, YAW])
    return np.sqrt(np.maximum(w @ (d * d), 0.0))


def initial_set(particles: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """A particle set of size ``n`` within joint limits, drawn with replacement when K != n.

    Parameters
    ----------
    particles : ndarray of shape (K, DOF)
        Poses (any shape reshaping to (K, DOF)).
    n : int
        Size of the set.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    ndarray of shape (n, DOF)
        The set, clipped to the joint limits.
    """
    particles = clip_to_limits(np.asarray(particles, dtype=np.float64).reshape(-1, DOF))
    if len(particles) != n:
        particles = particles[rng.integers(0, len(particles), n)]
    return particles


class AnnealedParticleFilter:
    """Annealed particle filter over 28-DOF poses.

    Parameters
    ----------
    n_layers : int, default=10
        Annealing layers M per frame (Deutscher: 10).
    n_particles : int, default=256
        N particles per layer; at least 2.
    survival : float, default=0.5
        Target survival rate alpha of every layer (Deutscher: 0.5), in (0, 1).
    diffusion : float, default=0.6
        Noise std as a fraction of the weighted particle spread after resampling.
    shrink : float, default=0.85
        Factor by which the diffusion shrinks each layer (Deutscher's alpha_m schedule).
    max_std : ndarray of shape (DOF,) or None, default=None
        Cap on the diffusion std (metres / radians); None: 0.1 m and 0.35 rad.
    min_std : ndarray of shape (DOF,) or None, default=None
        Floor of the diffusion std before shrinking (None: ``MIN_STD``); the tracker keeps it low
        so that the spread of the set, not the floor, sets the search.
    seed : int or numpy.random.Generator or None, default=0
        Seed or Generator of the filter's random numbers.

    Raises
    ------
    ValueError
        If ``n_layers < 1``, ``n_particles < 2`` or ``survival`` is not in (0, 1).
    """

    def __init__(
        self,
        n_layers: int = 10,
        n_particles: int = 256,
        survival: float = 0.5,
        diffusion: float = 0.6,
        shrink: float = 0.85,
        max_std: np.ndarray | None = None,
        min_std: np.ndarray | None = None,
        seed: int | np.random.Generator | None = 0,
    ) -> None:
        if n_layers < 1:
            raise ValueError(f"n_layers={n_layers}: need at least one annealing layer")
        if n_particles < 2:
            raise ValueError(f"n_particles={n_particles}: need at least two particles")
        if not 0 < survival < 1:
            raise ValueError(f"survival={survival!r}: must lie in (0, 1) (Deutscher uses 0.5)")
        self.n_layers = int(n_layers)
        self.n_particles = int(n_particles)
        self.survival = float(survival)
        self.diffusion = float(diffusion)
        self.shrink = float(shrink)
        self.max_std = np.where(np.arange(DOF) < 3, 0.1, 0.35) if max_std is None else np.asarray(max_std)
        self.min_std = MIN_STD if min_std is None else np.asarray(min_std)
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.particles: np.ndarray | None = None

    def initialise(self, particles: np.ndarray) -> None:
        """Set the particle set, K resampled to N if it differs.

        Parameters
        ----------
        particles : ndarray of shape (K, DOF)
            Initial poses.
        """
        self.particles = initial_set(particles, self.n_particles, self.rng)

    def step(
        self,
        log_likelihood: LogLikelihood,
        predict_fn: PredictFn | None = None,
        n_layers: int | None = None,
        min_std: np.ndarray | None = None,
        max_std: np.ndarray | None = None,
    ) -> Estimate:
        """Run one frame: predict, then the annealing layers.

        Parameters
        ----------
        log_likelihood : callable
            (N, DOF) poses -> (N,) log w(Z, x) of this frame's observation.
        predict_fn : callable or None, default=None
            (N, DOF) poses, rng -> (N, DOF): dynamics applied to last frame's particles; None: none.
        n_layers : int or None, default=None
            Annealing layers of this step; None: ``self.n_layers``.
        min_std, max_std : ndarray of shape (DOF,) or None, default=None
            Diffusion bounds of this step only (None: the filter's); a first search from a rough
            initial guess needs a wider one.

        Returns
        -------
        Estimate
            The frame's estimate.

        Raises
        ------
        RuntimeError
            If called before :meth:`initialise`.
        """
        return run_steps(self.steps(predict_fn, n_layers, min_std, max_std), log_likelihood)

    def steps(
        self,
        predict_fn: PredictFn | None = None,
        n_layers: int | None = None,
        min_std: np.ndarray | None = None,
        max_std: np.ndarray | None = None,
        first_layer: int = 0,
    ) -> Generator[np.ndarray, np.ndarray, Estimate]:
        """:meth:`step` as a generator, for a caller that evaluates the likelihood itself (of
        several people's particles at once): it yields each layer's (N, DOF) particles, is sent
        their (N,) log-likelihoods, and returns the Estimate.

        Parameters
        ----------
        predict_fn, n_layers, min_std, max_std
            As :meth:`step`.
        first_layer : int, default=0
            Index of the first of these layers in a longer schedule that an earlier frame began
            (the diffusion shrinks by ``shrink`` per layer from there): a search spread over
            several frames continues where the last one stopped.

        Yields
        ------
        ndarray of shape (N, DOF)
            The particles of the next layer to weigh.

        Returns
        -------
        Estimate
            The frame's estimate (``StopIteration.value``; :func:`run_steps` drives it).

        Raises
        ------
        RuntimeError
            If started before :meth:`initialise`.
        """
        lo = self.min_std if min_std is None else np.asarray(min_std)
        hi = self.max_std if max_std is None else np.asarray(max_std)
        if self.particles is None:
            raise RuntimeError("AnnealedParticleFilter.step before initialise(particles)")
        M = self.n_layers if n_layers is None else int(n_layers)
        P = self.particles
        if len(P) != self.n_particles:  # the count was changed (a time budget): the set redrawn to it
            P = initial_set(P, self.n_particles, self.rng)
        if predict_fn is not None:
            P = clip_to_limits(predict_fn(P, self.rng))
        betas, surv = np.empty(M), np.empty(M)
        n_evals = 0
        for m in range(M):
            ll = yield P
            n_evals += len(P)
            beta = choose_beta(ll, self.survival)
            w = _normalised(ll, beta)
            betas[m], surv[m] = beta, 1.0 / (len(w) * np.dot(w, w))
            if m == M - 1:
                mean = weighted_mean_pose(P, w)
                b = int(np.argmax(ll))
                # the annealed weights have ESS = survival x N by construction (beta is chosen so);
                # the ESS that says how well the set covers the posterior is that of the final set
                # weighted by the un-annealed density (beta = 1), before resampling
                w1 = _normalised(ll, 1.0)
                est_best, est_ll, ess = P[b].copy(), float(ll[b]), float(1.0 / np.dot(w1, w1))
            idx = systematic_resample(w, self.rng)
            P = P[idx]
            if m < M - 1:
                std = np.clip(
                    self.diffusion * weighted_std(P, np.full(len(P), 1.0 / len(P))), lo, hi
                ) * self.shrink ** (m + first_layer)
                P = clip_to_limits(P + self.rng.normal(size=P.shape) * std)
        self.particles = P
        return Estimate(mean, est_best, ess, est_ll, P, betas, surv, n_evals)


class ParticleFilter:
    """Plain SIR particle filter (CONDENSATION): one layer, weights from the raw likelihood.

    With ``n_particles = n_layers x N`` of the annealed filter it spends the same number of
    likelihood evaluations per frame; it is the baseline of Deutscher et al.'s comparison.

    Parameters
    ----------
    n_particles : int, default=2560
        Number of particles; at least 2.
    survival : float or None, default=0.5
        The likelihood exponent is chosen per frame for this survival rate (the fairest
        single-layer baseline: the same weighting as one annealing layer); None weights by the raw
        likelihood exp(l) as in CONDENSATION.
    seed : int or numpy.random.Generator or None, default=0
        Seed or Generator of the filter's random numbers.

    Raises
    ------
    ValueError
        If ``n_particles < 2``.
    """

    def __init__(
        self, n_particles: int = 2560, survival: float | None = 0.5, seed: int | np.random.Generator | None = 0
    ) -> None:
        self.survival = survival
        if n_particles < 2:
            raise ValueError(f"n_particles={n_particles}: need at least two particles")
        self.n_particles = int(n_particles)
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.particles: np.ndarray | None = None

    def initialise(self, particles: np.ndarray) -> None:
        """Set the particle set, K resampled to N if it differs.

        Parameters
        ----------
        particles : ndarray of shape (K, DOF)
            Initial poses.
        """
        self.particles = initial_set(particles, self.n_particles, self.rng)

    def step(
        self,
        log_likelihood: LogLikelihood,
        predict_fn: PredictFn | None = None,
        n_layers: int | None = None,
        min_std: np.ndarray | None = None,
        max_std: np.ndarray | None = None,
    ) -> Estimate:
        """Predict, weight by exp(log-likelihood), estimate, resample.

        Parameters
        ----------
        log_likelihood : callable
            (N, DOF) poses -> (N,) log w(Z, x) of this frame's observation.
        predict_fn : callable or None, default=None
            (N, DOF) poses, rng -> (N, DOF): dynamics applied to last frame's particles; None: none.
        n_layers, min_std, max_std : object
            Accepted for the annealed filter's interface and unused (one layer, no diffusion).

        Returns
        -------
        Estimate
            The frame's estimate.

        Raises
        ------
        RuntimeError
            If called before :meth:`initialise`.
        """
        return run_steps(self.steps(predict_fn), log_likelihood)

    def steps(
        self,
        predict_fn: PredictFn | None = None,
        n_layers: int | None = None,
        min_std: np.ndarray | None = None,
        max_std: np.ndarray | None = None,
        first_layer: int = 0,
    ) -> Generator[np.ndarray, np.ndarray, Estimate]:
        """:meth:`step` as a generator (as :meth:`AnnealedParticleFilter.steps`: one layer).

        Parameters
        ----------
        predict_fn, n_layers, min_std, max_std
            As :meth:`step`.
        first_layer : int, default=0
            Unused (one layer: no schedule to continue); for the annealed filter's signature.

        Yields
        ------
        ndarray of shape (N, DOF)
            The particles to weigh.

        Returns
        -------
        Estimate
            The frame's estimate.

        Raises
        ------
        RuntimeError
            If started before :meth:`initialise`.
        """
        if self.particles is None:
            raise RuntimeError("ParticleFilter.step before initialise(particles)")
        P = self.particles
        if predict_fn is not None:
            P = clip_to_limits(predict_fn(P, self.rng))
        ll = yield P
        w = _normalised(ll, 1.0 if self.survival is None else choose_beta(ll, self.survival))
        b = int(np.argmax(ll))
        est = Estimate(
            weighted_mean_pose(P, w),
            P[b].copy(),
            float(1.0 / np.dot(w, w)),
            float(ll[b]),
            P,
            np.ones(1),
            np.array([1.0 / (len(w) * np.dot(w, w))]),
            len(P),
        )
        self.particles = P[systematic_resample(w, self.rng)]
        est.particles = self.particles
        return est


__all__ = [
    "AnnealedParticleFilter",
    "ParticleFilter",
    "Estimate",
    "choose_beta",
    "survival_rate",
    "systematic_resample",
    "run_steps",
    "weighted_mean_pose",
    "weighted_std",
    "MIN_STD",
]
