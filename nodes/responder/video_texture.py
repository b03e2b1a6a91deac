"""The video-texture avatar: a texture motion graph over a recording of one person (Okwechime et al.,
"Social interactive human video synthesis").

Learning (:meth:`VideoTexture.fit`), from per-frame appearance features of the person's masked,
aligned image and per-frame social labels:

1. PCA of the appearance features to ``energy`` (98%) of the variance: eigenspace coordinates x_t.
2. Similarity over a window of ``window_s`` (0.25 s, W frames): frames are compared by the windowed
   distance d_W(i, j) = || [x_{i+k}]_k - [x_{j+k}]_k ||, k over the window (Schoedl et al.'s filtered
   distance), so that a cut joins frames that also move alike.
3. k-medoid clustering of the windowed frames (FasterPAM of the ``kmedoids`` package on the
   pairwise distances of at most ``max_cluster_frames`` frames). Cut points: a frame joins every
   cluster whose medoid lies within one radius (the ``radius`` quantile of the frames' distances to
   their nearest medoid), so a cut point may be in more than one cluster.
4. Pruning: a cluster keeps only the cut points whose state labels (gaze/talk/laugh) equal its
   medoid's: a cut never changes what the person is doing socially.
5. The texture motion graph over frames: playback edges t -> t + 1 and, for cut points i and j of
   one cluster, a jump i -> j + 1 (the ``max_jumps`` smoothest per cut point; no jump shorter
   than the window, which would only stutter). Dead ends are removed by keeping the largest
   strongly connected component (Tarjan, ``scipy.sparse.csgraph``); then one strongly connected
   subgraph per set of social signals (the largest SCC of the frames with that label set).
6. Transition likelihood: a kernel density estimate (scikit-learn ``KernelDensity``) of the pose
   likelihood in eigenspace, evaluated at each seam (the midpoint of the two frames it joins),
   times a Markov transition matrix between clusters (P(cluster at t + L | cluster at t), L =
   ``markov_lag_s``, from the recording), times the seam smoothness exp(-dev^2 / 2 sigma^2) where
   dev = || x_{i+1} - x_{j+1} || is how far the frame shown after the cut is from the one that would
   have followed (0 when playing on; sigma: the median frame-to-frame step), times exp(-jump_cost)
   per jump. Stored as one log-weight per edge.

Synthesis (:meth:`VideoTexture.step`): at a frame with several out-edges the next frame is drawn at
random with probability proportional to the edge weight times exp(-beta * sum_g s_g D_g(next)),
where D_g is the graph distance (frames) from the next frame to the nearest frame of goal g (a
requested signal such as ``nod``, or a signal-set subgraph such as ``state:gaze_at_other``) and s_g
the goal's strength: the likelihood-weighted random choice, steered towards what is asked for.
While a signal is requested (s_g >= 1) only transitions on a shortest way to it (within
``goal_slack`` frames) are drawn from, so a request is met as soon as the graph allows. A
cut is cross-faded over ``crossfade`` frames: the frames that would have followed fade out.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import cv2
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from counterpart.body.avatar_frames import AvatarFrames

#: the labels that define a frame's social state (pruning and signal-set subgraphs)
STATE_SIGNALS: tuple[str, ...] = ("gaze_at_other", "talking", "laughing")
#: goal names of the signal-set subgraphs: the prefix, then the signals on joined by "+" ("state:none": none)
STATE_PREFIX = "state:"

Progress = Callable[[str], None] | None


class RecordingError(ValueError):
    """A recording that cannot make an avatar (too short, a required signal missing)."""


@dataclass(frozen=True)
class VideoTextureConfig:
    """Parameters of the video texture (module docstring for their roles).

    Parameters
    ----------
    energy : float, default=0.98
        PCA variance kept.
    feature_size : tuple of int, default=(16, 32)
        (w, h) px of the masked grey image and mask features.
    window_s : float, default=0.25
        Similarity window, seconds.
    n_clusters : int, default=0
        k of the k-medoids (0: one per ``seconds_per_cluster`` of recording, 4-200).
    seconds_per_cluster : float, default=1.0
        Seconds of recording per cluster when ``n_clusters`` is 0.
    max_cluster_frames : int, default=2000
        Frames clustered at most (evenly spaced; all frames are then assigned).
    radius : float, default=0.75
        Quantile of the frames' distances to their nearest medoid that is the cut-point radius of every
        cluster.
    max_members : int, default=100
        Cut points a cluster keeps at most (its nearest; a person standing still would otherwise put
        thousands of frames in one cluster and its jumps would cost the square of that).
    max_jumps : int, default=12
        Jumps kept per cut point.
    markov_lag_s : float, default=0.25
        Lag of the cluster Markov chain, seconds.
    kde_dims : int, default=6
        Eigenspace dimensions of the KDE.
    kde_frames : int, default=1000
        Frames the KDE is fitted on at most.
    beta : float, default=1.0
        Steering per frame of goal distance (log-weight).
    jump_cost : float, default=6.0
        Log-weight a jump pays against playing on (without it the many jumps of a cut point outvote the
        one playback edge and the avatar flickers between near-identical frames).
    goal_slack : float, default=0.0
        Frames of detour allowed on the way to a requested signal (strength >= 1).
    crossfade : int, default=3
        Frames of a cut's cross-fade.
    min_seconds : float, default=8.0
        The shortest recording accepted, seconds.
    random_state : int, default=0
        Clustering and synthesis seed.
    """

    energy: float = 0.98
    feature_size: tuple[int, int] = (16, 32)
    window_s: float = 0.25
    n_clusters: int = 0
    seconds_per_cluster: float = 1.0
    max_cluster_frames: int = 2000
    radius: float = 0.75
    max_members: int = 100
    max_jumps: int = 12
    markov_lag_s: float = 0.25
    kde_dims: int = 6
    kde_frames: int = 1000
    beta: float = 1.0
    jump_cost: float = 6.0
    goal_slack: float = 0.0
    crossfade: int = 3
    min_seconds: float = 8.0
    random_state: int = 0


def appearance_features(crops: np.ndarray, masks: np.ndarray, size: tuple[int, int] = (16, 32)) -> np.ndarray:
    """Appearance feature of each masked, aligned frame: its grey image (background zero) and its
    mask, each resized to ``size`` (w, h) px by area averaging, concatenated.

    Parameters
    ----------
    crops : ndarray of shape (T, h, w, 3), dtype uint8
        Aligned BGR crops of the person.
    masks : ndarray of shape (T, h, w), dtype bool
        The person's mask in each crop.
    size : tuple of int, default=(16, 32)
        (w, h) px of each resized image.

    Returns
    -------
    ndarray of shape (T, 2 * w * h), dtype float32
        Grey image then mask features per frame, in [0, 1].
    """
    crops, masks = np.asarray(crops), np.asarray(masks, bool)
    out = np.empty((len(crops), 2 * size[0] * size[1]), np.float32)
    n = size[0] * size[1]
    for t in range(len(crops)):  # one small OpenCV call pair per frame; the pixels are vectorised
        m = masks[t].astype(np.float32)
        grey = cv2.cvtColor(crops[t], cv2.COLOR_BGR2GRAY).astype(np.float32) * (m / 255.0)
        out[t, :n] = cv2.resize(grey, size, interpolation=cv2.INTER_AREA).reshape(-1)
        out[t, n:] = cv2.resize(m, size, interpolation=cv2.INTER_AREA).reshape(-1)
    return out


def _runs(valid: np.ndarray) -> np.ndarray:
    """(T,) id of the run of consecutive valid frames each frame is in (-1 invalid)."""
    v = np.asarray(valid, bool)
    starts = v & ~np.r_[False, v[:-1]]
    rid = np.cumsum(starts) - 1
    return np.where(v, rid, -1)


def _pairwise(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, m) Euclidean distances between rows of a (n, d) and b (m, d), float64."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    d2 = (a * a).sum(1)[:, None] + (b * b).sum(1)[None, :] - 2.0 * a @ b.T
    return np.sqrt(np.maximum(d2, 0.0))


@dataclass
class _Recording:
    """The recording as :meth:`VideoTexture.fit`'s steps see it.

    x: (T, d) float32 eigenspace coordinates (NaN where the person was not found); valid: (T,)
    frames with the person; run: (T,) id of each frame's run of consecutive valid frames (-1
    invalid); nxt: (T,) frames whose next frame plays on in the same run; W: frames of a cut
    point's window; fps: frames per second; have: the number of valid frames.
    """

    x: np.ndarray
    valid: np.ndarray
    run: np.ndarray
    nxt: np.ndarray
    W: int
    fps: float
    have: int


def _windows(rec: _Recording) -> tuple[np.ndarray, np.ndarray]:
    """Windowed features: the frames wf whose whole window of W frames lies in one run of valid
    frames, and their windows' eigenspace coordinates Y (len(wf), W d).
    """
    x, valid, run, W = rec.x, rec.valid, rec.run, rec.W
    T, d = x.shape
    offs = np.arange(W) - W // 2
    idx = np.arange(T)[:, None] + offs[None, :]
    inside = (idx >= 0) & (idx < T)
    idc = np.clip(idx, 0, T - 1)
    wok = valid & inside.all(1) & (run[idc] == run[:, None]).all(1)
    wf = np.flatnonzero(wok)
    Y = x[idc[wf]].reshape(len(wf), W * d)
    return wf, Y


@dataclass
class _Synth:
    """Synthesis state."""

    cur: int = -1
    ghost: int = -1  # the frame that would have followed without the last cut
    fade: int = 0  # cross-fade frames left
    cuts: list[tuple[int, int]] = field(default_factory=list)


class VideoTexture:
    """A texture motion graph over one person's recording (module docstring).

    Parameters
    ----------
    config : VideoTextureConfig or None, default=None
        The texture's parameters (None: the defaults).

    Attributes
    ----------
    pca_mean_ : ndarray of shape (D,)
        Mean appearance feature.
    pca_components_ : ndarray of shape (d, D)
        Eigenspace basis.
    x_ : ndarray of shape (T, d)
        Eigenspace coordinates of each frame.
    medoids_ : ndarray of shape (k,)
        Frame indices of the cluster medoids.
    members_ : list of ndarray
        Cut-point frames per cluster.
    alive_ : ndarray of shape (T,), dtype bool
        Frames of the graph.
    indptr_, indices_, logw_ : ndarray
        The graph's out-edges in CSR form with their log-weights.
    goals_ : list of str
        Goal names.
    dist_ : ndarray of shape (G, T), dtype float32
        Graph distances in frames to each goal (inf: unreachable).
    labels_ : ndarray of shape (T, K), dtype int8
        Social labels of each frame (1 present, 0 absent, -1 unknown).
    names_ : list of str
        The K signal names.
    step_q95_ : float
        The recording's 95th percentile frame-to-frame distance in eigenspace.
    frames : AvatarFrames or None
        The :class:`~counterpart.body.avatar_frames.AvatarFrames` when given.
    """

    name = "video-texture"

    def __init__(self, config: VideoTextureConfig | None = None) -> None:
        self.config = config or VideoTextureConfig()
        self.frames: AvatarFrames | None = None
        self.fps = 25.0
        self.training_: dict[str, Any] = {}

    # ---------------------------------------------------------------------------------- learning
    def fit(
        self,
        features: np.ndarray,
        labels: np.ndarray,
        names: Sequence[str],
        fps: float,
        valid: np.ndarray | None = None,
        required: Sequence[str] = (),
        frames: AvatarFrames | None = None,
        progress: Progress = None,
    ) -> VideoTexture:
        """Learn the graph (on one BLAS thread: the matrices are small, and a second thread on a
        busy machine makes the eigendecomposition ten times slower, not faster).

        Parameters
        ----------
        features : ndarray of shape (T, D)
            Appearance features (:func:`appearance_features`).
        labels : ndarray of shape (T, K), dtype int8
            Social labels (1 present, 0 absent, -1 unknown) named ``names``.
        names : sequence of str
            The K signal names.
        fps : float
            Frames per second.
        valid : ndarray of shape (T,), dtype bool, optional
            Frames where the person was found (default all).
        required : sequence of str, default=()
            Signals the avatar must be able to show.
        frames : AvatarFrames or None, default=None
            The recording's masked frames, stored with the model.
        progress : callable or None, default=None
            Called with a line of progress text.

        Returns
        -------
        VideoTexture
            self, fitted.

        Raises
        ------
        RecordingError
            For a recording that cannot make an avatar, naming the cause (too short, a required signal
            missing).
        """
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1):
            return self._fit(features, labels, names, fps, valid, required, frames, progress)

    def _fit(
        self,
        features: np.ndarray,
        labels: np.ndarray,
        names: Sequence[str],
        fps: float,
        valid: np.ndarray | None,
        required: Sequence[str],
        frames: AvatarFrames | None,
        progress: Progress,
    ) -> VideoTexture:
        """:meth:`fit`'s steps: check the recording, its eigenspace and playback, the cut-point
        clusters, the jumps within them, the graph without dead ends, the transitions' likelihoods,
        the goals and their graph distances.
        """
        say = progress or (lambda s: None)
        X = np.asarray(features, np.float32)
        L, names, valid, have = self._check_recording(len(X), labels, names, fps, valid, required)
        self.fps = float(fps)
        x = self._eigenspace(X, valid, have, say)
        run, nxt = self._playback(x, valid)
        rec = _Recording(x, valid, run, nxt, max(int(round(self.config.window_s * fps)), 1), fps, have)
        wf, Y = _windows(rec)
        nearest, state, k = self._cut_points(rec, wf, Y, L, names, say)
        src, dst, seam = self._jumps(rec)
        e_src, e_dst, e_seam = self._graph(rec, src, dst, seam, say)
        self._transitions(rec, nearest, k, e_src, e_dst, e_seam, say)
        self._goals(rec, L, names, state, required, say)
        self.frames = frames
        self.reset()
        return self

    def _check_recording(
        self,
        T: int,
        labels: np.ndarray,
        names: Sequence[str],
        fps: float,
        valid: np.ndarray | None,
        required: Sequence[str],
    ) -> tuple[np.ndarray, list[str], np.ndarray, int]:
        """The labels (T, K) int8, the names, the valid frames (T,) and their count; a
        RecordingError saying what is missing when the recording cannot make an avatar.
        """
        c = self.config
        L = np.asarray(labels).astype(np.int8)
        names = list(names)
        if L.shape != (T, len(names)):
            raise RecordingError(f"labels {L.shape} do not match {T} frames x {len(names)} names")
        valid = np.ones(T, bool) if valid is None else np.asarray(valid, bool)
        have = int(valid.sum())
        if have < c.min_seconds * fps:
            raise RecordingError(
                f"the recording has {have / fps:.1f} s with the person in view ({have} frames); "
                f"an avatar needs at least {c.min_seconds:g} s: record for longer (a minute "
                "or more gives a lively avatar)"
            )
        for r in required:
            if r not in names:
                raise RecordingError(
                    f"signal {r!r} is not among the labels ({', '.join(names)}); give labels "
                    f"that include it, or leave it out of --signals"
                )
            if not (L[valid, names.index(r)] == 1).any():
                raise RecordingError(
                    f"signal {r!r} never occurs in the recording (0 of {have} frames labelled "
                    f"{r}): record the person doing it, or leave it out of --signals"
                )
        return L, names, valid, have

    def _eigenspace(self, X: np.ndarray, valid: np.ndarray, have: int, say: Callable[[str], None]) -> np.ndarray:
        """PCA of the valid frames' features (T, D) -> eigenspace coordinates (T, d) float32, NaN
        where the person was not found.
        """
        c = self.config
        T = len(X)
        say(f"eigenspace: PCA of {have} frames to {c.energy:.0%} of the energy")
        from sklearn.decomposition import PCA

        pca = PCA(n_components=c.energy, svd_solver="covariance_eigh", random_state=c.random_state).fit(X[valid])
        x = np.full((T, pca.n_components_), np.nan, np.float32)
        x[valid] = pca.transform(X[valid])
        self.pca_mean_, self.pca_components_ = pca.mean_.astype(np.float32), pca.components_.astype(np.float32)
        self.x_ = x
        return x

    def _playback(self, x: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The recording's runs of valid frames (T,) and the frames whose next one plays on in the
        same run (T,); the steps between them set the scale of every distance below.
        """
        run = _runs(valid)
        nxt = np.r_[run[1:] == run[:-1], False] & valid
        steps = np.linalg.norm(x[1:] - x[:-1], axis=1)[nxt[:-1]]
        self.step_median_ = float(np.median(steps)) if len(steps) else 1.0
        self.step_q95_ = float(np.percentile(steps, 95)) if len(steps) else 1.0
        return run, nxt

    def _cut_points(
        self,
        rec: _Recording,
        wf: np.ndarray,
        Y: np.ndarray,
        L: np.ndarray,
        names: list[str],
        say: Callable[[str], None],
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """Cut-point clusters: k-medoids (FasterPAM) of the windowed frames ``wf`` (features Y),
        members within the ``radius`` quantile of their medoid, pruned to the medoid's social state.
        Returns each frame's nearest medoid (T,) (-1: not windowed), the social state (T, S) and k.
        """
        c = self.config
        have, fps, W, T = rec.have, rec.fps, rec.W, len(rec.x)
        k = c.n_clusters or int(np.clip(round(have / fps / c.seconds_per_cluster), 4, 200))
        k = min(k, len(wf) // 2)
        sub = (
            wf if len(wf) <= c.max_cluster_frames else wf[np.linspace(0, len(wf) - 1, c.max_cluster_frames).astype(int)]
        )
        say(f"cut-point clusters: k-medoids (FasterPAM), k={k}, on {len(sub)} frames, window {W} frames")
        import kmedoids

        pos = np.searchsorted(wf, sub)
        D = _pairwise(Y[pos], Y[pos])
        # random initialisation: FasterPAM's swaps make up for it, and BUILD costs k n^2
        res = kmedoids.fasterpam(D, k, max_iter=100, init="random", random_state=c.random_state, n_cpu=1)
        self.medoids_ = sub[np.asarray(res.medoids, np.int64)]
        Dm = _pairwise(Y, Y[np.searchsorted(wf, self.medoids_)]) / np.sqrt(W)  # (n windowed, k) per frame
        nearest = np.full(T, -1, np.int64)
        nearest[wf] = np.argmin(Dm, axis=1)
        state_cols = [names.index(s) for s in STATE_SIGNALS if s in names]
        state = (L[:, state_cols] == 1) if state_cols else np.zeros((T, 0), bool)
        rho = float(np.quantile(Dm.min(axis=1), c.radius))
        member = Dm <= rho
        # pruning: a cluster keeps the cut points with its medoid's social state
        same = (state[wf][:, None, :] == state[self.medoids_][None, :, :]).all(-1)
        member &= same
        far_rank = np.argsort(np.argsort(np.where(member, Dm, np.inf), axis=0, kind="stable"), axis=0)
        member &= far_rank < c.max_members
        self.members_ = [wf[member[:, j]] for j in range(k)]
        n_cut = int(member.any(1).sum())
        say(
            f"{n_cut} cut points in {sum(len(m) >= 2 for m in self.members_)} clusters after pruning by "
            f"{', '.join(STATE_SIGNALS[i] for i, s in enumerate(STATE_SIGNALS) if s in names) or 'no labels'}"
        )
        return nearest, state, k

    def _jumps(self, rec: _Recording) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Jumps i -> j + 1 between members i, j of a cluster (at least a window apart): source and
        landing frames and the seam's eigenspace distance, thinned to the smoothest per source.
        """
        c = self.config
        x, valid, run, W, T = rec.x, rec.valid, rec.run, rec.W, len(rec.x)
        src, dst, seam = [], [], []
        for m in self.members_:
            if len(m) < 2:
                continue
            land = m + 1
            ok = land < T
            ok[ok] &= valid[land[ok]] & (run[land[ok]] == run[m[ok]])
            i_, j_ = np.meshgrid(m, m[ok], indexing="ij")
            s_ = np.broadcast_to(land[ok][None, :], i_.shape)
            far = np.abs(j_ - i_) >= W
            if not far.any():
                continue
            dd = _pairwise(x[m], x[land[ok]])[far]
            src.append(i_[far]), dst.append(s_[far]), seam.append(dd)
        src = np.concatenate(src) if src else np.zeros(0, np.int64)
        dst = np.concatenate(dst) if dst else np.zeros(0, np.int64)
        seam = np.concatenate(seam) if seam else np.zeros(0)
        # one edge per source and stretch of W landing frames (the smoothest: cut points in several
        # clusters, neighbouring landings), so the kept jumps lead to many places of the recording;
        # then the smoothest max_jumps per source
        order = np.lexsort((seam, dst // W, src))
        src, dst, seam = src[order], dst[order], seam[order]
        first = np.r_[True, (src[1:] != src[:-1]) | (dst[1:] // W != dst[:-1] // W)]
        src, dst, seam = src[first], dst[first], seam[first]
        order = np.lexsort((seam, src))
        src, dst, seam = src[order], dst[order], seam[order]
        start = np.r_[0, np.flatnonzero(src[1:] != src[:-1]) + 1] if len(src) else np.zeros(0, np.int64)
        rank = np.arange(len(src)) - np.repeat(start, np.diff(np.r_[start, len(src)])) if len(src) else src
        keep = rank < c.max_jumps
        src, dst, seam = src[keep], dst[keep], seam[keep]
        return src, dst, seam

    def _graph(
        self, rec: _Recording, src: np.ndarray, dst: np.ndarray, seam: np.ndarray, say: Callable[[str], None]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The texture motion graph: playback edges and jumps, kept within the largest strongly
        connected component (no dead ends, Tarjan); returns its edges' sources, targets and seams.
        """
        x, valid, nxt, W, T = rec.x, rec.valid, rec.nxt, rec.W, len(rec.x)
        play = np.flatnonzero(nxt)
        e_src = np.r_[play, src].astype(np.int64)
        e_dst = np.r_[play + 1, dst].astype(np.int64)
        e_seam = np.r_[np.linalg.norm(x[play + 1] - x[play], axis=1), seam]
        say(f"texture motion graph: {len(play)} playback edges, {len(src)} jumps; removing dead ends (Tarjan)")
        G = csr_matrix((np.ones(len(e_src)), (e_src, e_dst)), shape=(T, T))
        n_comp, comp = connected_components(G, directed=True, connection="strong")
        sizes = np.bincount(comp[valid], minlength=n_comp)
        alive = valid & (comp == int(np.argmax(sizes)))
        keep = alive[e_src] & alive[e_dst]
        e_src, e_dst, e_seam = e_src[keep], e_dst[keep], e_seam[keep]
        self.alive_ = alive
        if alive.sum() < W * 4:
            raise RecordingError(
                f"the recording's frames do not join up into a loop ({int(alive.sum())} frames "
                "would remain): record for longer, returning to the same rest pose now and then"
            )
        return e_src, e_dst, e_seam

    def _transitions(
        self,
        rec: _Recording,
        nearest: np.ndarray,
        k: int,
        e_src: np.ndarray,
        e_dst: np.ndarray,
        e_seam: np.ndarray,
        say: Callable[[str], None],
    ) -> None:
        """The log-likelihood of each edge: KDE of poses at the seam x Markov chain between the
        clusters x smoothness, minus the jump cost; the edges stored in CSR order.
        """
        c = self.config
        x, valid, run, fps, alive = rec.x, rec.valid, rec.run, rec.fps, self.alive_
        T, d = x.shape
        say("transition likelihood: KDE of poses in eigenspace, Markov chain between clusters")
        from sklearn.neighbors import KernelDensity

        q = min(c.kde_dims, d)
        xa = x[alive][:, :q].astype(np.float64)
        sd = xa.std(0) + 1e-9
        rng = np.random.default_rng(c.random_state)
        fit_rows = xa if len(xa) <= c.kde_frames else xa[rng.choice(len(xa), c.kde_frames, replace=False)]
        bw = float(len(fit_rows) ** (-1.0 / (q + 4)))  # Scott's rule on standardised coordinates
        kde = KernelDensity(bandwidth=bw, rtol=1e-2).fit(fit_rows / sd)  # 1%: a log-weight needs no more
        mid = 0.5 * (x[e_src, :q] + x[e_dst, :q]).astype(np.float64) / sd
        ll = kde.score_samples(mid)
        lag = max(int(round(c.markov_lag_s * fps)), 1)
        a, b = nearest[:-lag], nearest[lag:]
        ok = (a >= 0) & (b >= 0) & (run[:-lag] == run[lag:])
        counts = np.full((k, k), 0.1)
        np.add.at(counts, (a[ok], b[ok]), 1.0)
        self.markov_ = (counts / counts.sum(1, keepdims=True)).astype(np.float32)
        ahead = np.minimum(e_dst + lag, T - 1)
        ahead = np.where((run[ahead] == run[e_dst]) & (nearest[ahead] >= 0), ahead, e_dst)
        ca, cb = nearest[e_src], nearest[ahead]
        lm = np.where(
            (ca >= 0) & (cb >= 0), np.log(self.markov_[np.maximum(ca, 0), np.maximum(cb, 0)]), np.log(1.0 / k)
        )
        sigma = max(self.step_median_, 1e-6)
        is_jump = e_dst != e_src + 1
        after = np.minimum(e_src + 1, T - 1)
        dev = np.where(is_jump & valid[after], np.linalg.norm(x[after] - x[e_dst], axis=1), 0.0)
        dev = np.where(is_jump & ~valid[after], e_seam, dev)
        logw = (ll - np.median(ll)) + lm - 0.5 * (dev / sigma) ** 2 - c.jump_cost * is_jump
        order = np.lexsort((e_dst, e_src))
        self.e_src_, self.e_dst_ = e_src[order], e_dst[order]
        self.seam_ = e_seam[order].astype(np.float32)
        self.logw_ = np.clip(logw[order], -50, 50).astype(np.float32)
        self.indptr_ = np.r_[0, np.cumsum(np.bincount(self.e_src_, minlength=T))].astype(np.int64)
        self.indices_ = self.e_dst_

    def _goals(
        self,
        rec: _Recording,
        L: np.ndarray,
        names: list[str],
        state: np.ndarray,
        required: Sequence[str],
        say: Callable[[str], None],
    ) -> None:
        """Goals: every signal that occurs in the graph, and one subgraph per set of social signals
        with a loop of its own; the graph distance of every frame to each.
        """
        W, T, alive = rec.W, len(rec.x), self.alive_
        self.labels_, self.names_ = L, names
        goals, targets = [], []
        for kk, nm in enumerate(names):
            on = alive & (L[:, kk] == 1)
            if on.any():
                goals.append(nm)
                targets.append(on)
            else:
                say(f"note: {nm!r} never occurs in the graph: the avatar cannot show it")
        for r in required:
            if r not in goals:
                raise RecordingError(
                    f"signal {r!r} occurs only where the recording cannot loop back (a dead end); "
                    "record it once more in the middle of the recording"
                )
        Ga = csr_matrix((np.ones(len(self.e_src_)), (self.e_src_, self.e_dst_)), shape=(T, T))
        codes = state @ (1 << np.arange(state.shape[1])) if state.shape[1] else np.zeros(T, np.int64)
        sub_names = [STATE_SIGNALS[i] for i, s in enumerate(STATE_SIGNALS) if s in names]
        for code in np.unique(codes[alive]):
            inset = alive & (codes == code)
            keep_e = inset[self.e_src_] & inset[self.e_dst_]
            S = csr_matrix((np.ones(int(keep_e.sum())), (self.e_src_[keep_e], self.e_dst_[keep_e])), shape=(T, T))
            nc, cc = connected_components(S, directed=True, connection="strong")
            sz = np.bincount(cc[inset], minlength=nc)
            best = int(np.argmax(sz))
            if sz[best] < 2 * W:
                continue  # no loop of its own: the avatar could not stay in this state
            goals.append(STATE_PREFIX + ("+".join(n for i, n in enumerate(sub_names) if code >> i & 1) or "none"))
            targets.append(inset & (cc == best))
        say(f"graph distances to {len(goals)} goals: {', '.join(goals)}")
        self.goals_ = goals
        self.dist_ = (
            np.stack([self._distance_to(Ga, t) for t in targets]).astype(np.float32)
            if targets
            else np.zeros((0, T), np.float32)
        )

    @staticmethod
    def _distance_to(G: csr_matrix, target: np.ndarray) -> np.ndarray:
        """(T,) frames from each frame to the nearest ``target`` frame along the graph (inf: none)."""
        src = np.flatnonzero(target)
        return dijkstra(G.T.tocsr(), directed=True, indices=src, unweighted=True, min_only=True)

    # ---------------------------------------------------------------------------------- synthesis
    def reset(self, start: int | None = None) -> None:
        """Start again at frame ``start``.

        Parameters
        ----------
        start : int or None, default=None
            Recording frame to start at (None: the first frame of the graph).

        Raises
        ------
        ValueError
            When ``start`` is not in the texture motion graph.
        """
        self._rng = np.random.default_rng(self.config.random_state)
        first = int(np.flatnonzero(self.alive_)[0]) if start is None else int(start)
        if not self.alive_[first]:
            raise ValueError(f"frame {first} is not in the texture motion graph")
        self._s = _Synth(cur=first)

    @property
    def current(self) -> int:
        """The recording frame shown last."""
        return self._s.cur

    def goal_index(self, name: str) -> int:
        """Index of goal ``name`` in ``goals_``.

        Parameters
        ----------
        name : str
            Goal name (a signal, or ``state:...``).

        Returns
        -------
        int
            The index; -1 when the graph does not have it.
        """
        try:
            return self.goals_.index(name)
        except ValueError:
            return -1

    def state_goal(self, wanted: Mapping[str, bool]) -> str | None:
        """The signal-set subgraph closest to the wanted state (signal -> on): the most agreeing
        signals, ties to the first.

        Parameters
        ----------
        wanted : mapping of str to bool
            Signal name -> on.

        Returns
        -------
        str or None
            The goal name ``state:...``; None when the graph has no state subgraphs.
        """
        best, score = None, -1
        for g in self.goals_:
            if not g.startswith(STATE_PREFIX):
                continue
            on = set(g[len(STATE_PREFIX) :].split("+")) - {"none"}
            s = sum((n in on) == bool(v) for n, v in wanted.items())
            if s > score:
                best, score = g, s
        return best

    def step(self, goals: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Advance one output frame.

        Parameters
        ----------
        goals : mapping of str to float, optional
            Goal name (a signal such as ``nod``, or ``state:...``) -> strength >= 0; goals the graph does
            not have are ignored.

        Returns
        -------
        frames : ndarray of shape (n,), dtype int32
            Recording frame indices: one frame, or two during a cut's cross-fade.
        weights : ndarray of shape (n,), dtype float32
            Blend weights of ``frames``, summing to 1.
        """
        s = self._s
        a, b = self.indptr_[s.cur], self.indptr_[s.cur + 1]
        options = self.indices_[a:b]
        if len(options) == 1:
            nxt = int(options[0])
        else:
            score = self.logw_[a:b].astype(np.float64)
            cost, firm = np.zeros(len(options)), np.zeros(len(options))
            for g, strength in (goals or {}).items():
                gi = self.goal_index(g)
                if gi >= 0 and strength > 0:
                    dg = self.dist_[gi, options].astype(np.float64)
                    dg = np.where(np.isfinite(dg), dg, 1e4)
                    cost += strength * dg
                    if strength >= 1.0:
                        firm += dg
            score -= self.config.beta * (cost - cost.min())
            # a requested signal: only the transitions on a shortest way to it (within the slack)
            score[firm > firm.min() + self.config.goal_slack] = -np.inf
            p = np.exp(score - score.max())
            nxt = int(options[self._rng.choice(len(options), p=p / p.sum())])
        if nxt != s.cur + 1:
            s.cuts.append((s.cur, nxt))
            nat = s.cur + 1
            s.ghost = nat if nat < len(self.alive_) and self.x_[nat, 0] == self.x_[nat, 0] else -1
            s.fade = self.config.crossfade if s.ghost >= 0 else 0
        elif s.fade:
            s.ghost += 1
            if s.ghost >= len(self.alive_) or self.x_[s.ghost, 0] != self.x_[s.ghost, 0]:
                s.fade = 0
        s.cur = nxt
        if s.fade > 0:
            w_old = s.fade / (self.config.crossfade + 1)
            s.fade -= 1
            return np.array([nxt, s.ghost], np.int32), np.array([1.0 - w_old, w_old], np.float32)
        return np.array([nxt], np.int32), np.ones(1, np.float32)

    def labels_at(self, t: int) -> dict[str, bool]:
        """The social signals of a recording frame.

        Parameters
        ----------
        t : int
            Recording frame index.

        Returns
        -------
        dict of str to bool
            Signal name -> on (label 1).
        """
        return {n: bool(v == 1) for n, v in zip(self.names_, self.labels_[int(t)])}

    # ------------------------------------------------------------------------------ persistence
    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The fitted model for a model file (:func:`~counterpart.nodes.responder.models.save_model`).

        Returns
        -------
        arrays : dict of str to ndarray
            The graph, eigenspace, labels, cluster members and (when attached) the frames.
        config : dict
            JSON-able configuration, frame rate, names, goals and step statistics.
        """
        arrays = {
            "pca_mean": self.pca_mean_,
            "pca_components": self.pca_components_,
            "x": self.x_,
            "medoids": self.medoids_,
            "alive": self.alive_,
            "indptr": self.indptr_,
            "indices": self.indices_,
            "logw": self.logw_,
            "seam": self.seam_,
            "dist": self.dist_,
            "labels": self.labels_,
            "markov": self.markov_,
        }
        for j, m in enumerate(self.members_):
            arrays[f"members_{j}"] = m
        if self.frames is not None:
            arrays.update(self.frames.arrays())
        config = {
            "config": {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self.config).items()},
            "fps": self.fps,
            "names": list(self.names_),
            "goals": list(self.goals_),
            "n_members": len(self.members_),
            "step_median": self.step_median_,
            "step_q95": self.step_q95_,
        }
        return arrays, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> VideoTexture:
        """The model from :meth:`get_state`'s output, reset to the first frame of its graph.

        Parameters
        ----------
        arrays : dict of str to ndarray
            As :meth:`get_state` returns them.
        config : dict
            As :meth:`get_state` returns it.

        Returns
        -------
        VideoTexture
            The fitted model.
        """
        cfg = {k: tuple(v) if isinstance(v, list) else v for k, v in config["config"].items()}
        m = cls(VideoTextureConfig(**cfg))
        m.fps = float(config["fps"])
        m.pca_mean_, m.pca_components_, m.x_ = arrays["pca_mean"], arrays["pca_components"], arrays["x"]
        m.medoids_, m.alive_ = arrays["medoids"], arrays["alive"].astype(bool)
        m.indptr_, m.indices_ = arrays["indptr"].astype(np.int64), arrays["indices"].astype(np.int64)
        m.e_dst_ = m.indices_
        m.e_src_ = np.repeat(np.arange(len(m.indptr_) - 1), np.diff(m.indptr_))
        m.logw_, m.seam_, m.dist_ = arrays["logw"], arrays["seam"], arrays["dist"]
        m.labels_, m.markov_ = arrays["labels"], arrays["markov"]
        m.members_ = [arrays[f"members_{j}"] for j in range(int(config["n_members"]))]
        m.names_, m.goals_ = list(config["names"]), list(config["goals"])
        m.step_median_, m.step_q95_ = float(config["step_median"]), float(config["step_q95"])
        m.frames = AvatarFrames.from_arrays(arrays) if "frames_jpeg" in arrays else None
        m.reset()
        return m


def fit_recording(
    rec: Any, config: VideoTextureConfig | None = None, required: Sequence[str] = (), progress: Progress = None
) -> VideoTexture:
    """Learn an avatar from a :class:`~counterpart.nodes.responder.avatar_recording.Recording`: appearance
    features, the compressed masked frames and the texture motion graph.

    Parameters
    ----------
    rec : Recording
        The recording (``crops``, ``masks``, ``facing``, ``labels``, ``names``, ``fps``, ``valid``).
    config : VideoTextureConfig or None, default=None
        The texture's parameters (None: the defaults).
    required : sequence of str, default=()
        Signals the avatar must be able to show.
    progress : callable or None, default=None
        Called with a line of progress text.

    Returns
    -------
    VideoTexture
        The fitted model, its frames attached.

    Raises
    ------
    RecordingError
        As :meth:`VideoTexture.fit`.
    """
    say = progress or (lambda s: None)
    model = VideoTexture(config)
    say(f"appearance features of {len(rec.crops)} masked {rec.crops.shape[2]}x{rec.crops.shape[1]} frames")
    feats = appearance_features(rec.crops, rec.masks, model.config.feature_size)
    say("compressing the masked frames (JPEG + packed masks)")
    frames = AvatarFrames.encode(rec.crops, rec.masks, rec.facing)
    return model.fit(
        feats, rec.labels, rec.names, rec.fps, valid=rec.valid, required=required, frames=frames, progress=say
    )
