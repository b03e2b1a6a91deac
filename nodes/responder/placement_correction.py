"""The dual HMM's placement correction: a regression forest over causal features of each frame.

While the two people are still walking up or standing, the interaction, and with it where the
partner stands (a wave's partner 2.5 m away, a push's 1.3 m and walking in), is ambiguous; the
tracked placement then mixes the labels' placements in the proportions of the tempered posterior,
which is not calibrated for this. A regression forest (extremely randomised trees, scikit-learn)
learns the error of the placement (true minus generated ground position x, z, metres) from the
features of :class:`CorrectionFeatures`; its prediction is added to the placement. The model fits
it by cross-fitting (:func:`deal_folds`): models fitted without one fold of the training sequences
are run online on that fold, so that the errors learnt are those of unseen sequences. Online, the
fitted forest is walked as plain arrays (:class:`ForestArrays`), all trees together.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

#: the observed person's motion summaries in the features: seconds since the sequence started,
#: mean ground speed over the last frames, its maximum so far (m/s), the ground path walked so far
#: (m); capped where longer histories tell nothing more about the approach
_T_CAP_S, _PATH_CAP_M, _SPEED_FRAMES = 6.0, 2.0, 5


class ForestArrays:
    """A fitted regression forest (scikit-learn's tree arrays, padded to one width) as plain arrays.

    Parameters
    ----------
    feature, threshold, left, right : ndarray of shape (n_trees, n_nodes)
        Split feature index, threshold, child nodes (-1 at a leaf). A sample goes left where
        x[feature] <= threshold.
    value : ndarray of shape (n_trees, n_nodes, n_out)
        The node means; the prediction is the mean over trees of the leaf values.
    """

    def __init__(
        self, feature: np.ndarray, threshold: np.ndarray, left: np.ndarray, right: np.ndarray, value: np.ndarray
    ) -> None:
        self.feature, self.threshold = np.asarray(feature, np.intp), np.asarray(threshold, np.float64)
        self.left, self.right, self.value = np.asarray(left, np.intp), np.asarray(right, np.intp), np.asarray(value)
        self._rows = np.arange(len(self.feature))
        # the trees' nodes in one flat array each (tree t's node k at t * n_nodes + k): one-dimensional
        # takes cost less than the two-dimensional fancy indexing of each step
        n = self.feature.shape[1] if self.feature.ndim == 2 else 0
        self._base = self._rows * n
        self._flat = (self.feature.ravel(), self.threshold.ravel(), self.left.ravel(), self.right.ravel())
        self._flat_value = self.value.reshape(len(self.feature) * n, -1) if n else self.value

    @classmethod
    def from_sklearn(cls, forest: Any) -> ForestArrays:
        """The arrays of a fitted scikit-learn forest regressor.

        Parameters
        ----------
        forest : sklearn.ensemble forest regressor
            Fitted (``estimators_`` of trees).

        Returns
        -------
        ForestArrays
            The forest's trees, padded to the largest node count.
        """
        trees = [e.tree_ for e in forest.estimators_]
        n, d = max(t.node_count for t in trees), trees[0].value.shape[1]
        F, L, R = (
            np.zeros((len(trees), n), np.int32),
            np.full((len(trees), n), -1, np.int32),
            np.full((len(trees), n), -1, np.int32),
        )
        th, V = np.zeros((len(trees), n)), np.zeros((len(trees), n, d))
        for i, t in enumerate(trees):
            k = t.node_count
            F[i, :k], th[i, :k] = np.maximum(t.feature, 0), t.threshold
            L[i, :k], R[i, :k], V[i, :k] = t.children_left, t.children_right, t.value[:, :, 0]
        return cls(F, th, L, R, V)

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of a model file.

        Returns
        -------
        dict of str to ndarray
            ``feature``, ``threshold``, ``left``, ``right`` (int32 or float64, (n_trees, n_nodes)) and
            ``value`` ((n_trees, n_nodes, n_out)).
        """
        return {
            "feature": self.feature.astype(np.int32),
            "threshold": self.threshold,
            "left": self.left.astype(np.int32),
            "right": self.right.astype(np.int32),
            "value": self.value,
        }

    def predict(self, x: np.ndarray) -> np.ndarray:
        """The forest's mean prediction; all trees walked together.

        Parameters
        ----------
        x : ndarray of shape (d,)
            Features of one sample.

        Returns
        -------
        ndarray of shape (n_out,)
            The mean over trees of the leaf values.
        """
        # scikit-learn splits on float32 features: compare the same rounded values
        x = np.asarray(x, np.float32).astype(np.float64)
        feature, threshold, left_of, right_of = self._flat
        node = self._base.copy()  # each tree's root, as a flat node index
        while True:
            left = left_of[node]
            inner = left >= 0
            if not inner.any():
                return self._flat_value[node].mean(0)
            go_left = x[feature[node]] <= threshold[node]
            node = np.where(inner, self._base + np.where(go_left, left, right_of[node]), node)


def fit_forest(X: np.ndarray, Y: np.ndarray, trees: int, leaf: int, random_state: int) -> ForestArrays:
    """Extremely randomised trees fitted to placement errors.

    Parameters
    ----------
    X : ndarray of shape (F, d)
        Features of each frame.
    Y : ndarray of shape (F, 2)
        Placement errors (true minus generated ground position x, z), metres.
    trees : int
        Number of trees.
    leaf : int
        Least number of frames in a leaf.
    random_state : int
        Seed of the forest.

    Returns
    -------
    ForestArrays
        The fitted forest.
    """
    from sklearn.ensemble import ExtraTreesRegressor

    forest = ExtraTreesRegressor(trees, min_samples_leaf=leaf, max_features=1.0, random_state=random_state)
    return ForestArrays.from_sklearn(forest.fit(X, Y))


def deal_folds(labels: Sequence[str], folds: int) -> np.ndarray:
    """Fold of each training sequence: each label's sequences dealt round the folds in turn.

    Parameters
    ----------
    labels : sequence of str
        Label of each of the S training sequences.
    folds : int
        Number of folds.

    Returns
    -------
    ndarray of shape (S,)
        int fold of each sequence, in ``0 .. folds - 1``.
    """
    labels = np.asarray(labels)
    fold = np.zeros(len(labels), int)
    for g in np.unique(labels):
        idx = np.flatnonzero(labels == g)
        fold[idx] = np.arange(len(idx)) % folds
    return fold


class CorrectionFeatures:
    """The correction's features of each frame of a sequence, (2 + 3 L + 4,) for L labels.

    Parameters
    ----------
    label_member : ndarray of shape (L, N)
        1 where state k belongs to label l, else 0 (fixed per model).
    fps : float
        Frames per second of the sequence.

    Features: the placement; the posterior mass of each label's states; the seconds since the
    sequence started, the observed ground speed averaged over the last frames, its maximum so far
    and the path walked (capped); each label's posterior-weighted conditional distance z (metres; 0
    where the label has no mass) and its difference to the placement's. While the interaction is
    unclear the tracked placement mixes the labels' placements in the proportions of a tempered
    posterior; these let the correction reweigh them by how far into the sequence, and how far and
    fast the observed person has come.
    """

    def __init__(self, label_member: np.ndarray, fps: float) -> None:
        self.label_member, self.fps = label_member, float(fps)
        self.reset()

    def reset(self) -> None:
        """Forget the sequence's motion: frames, last ground speeds (m/s), fastest smoothed speed
        (m/s), path walked (m).
        """
        self._n_seen, self._speeds, self._top_speed, self._path = 0, [], 0.0, 0.0

    def __call__(self, pos: np.ndarray, z_k: np.ndarray, posterior: np.ndarray, speed: float) -> np.ndarray:
        """The features of this frame.

        Parameters
        ----------
        pos : ndarray of shape (2,)
            The model's placement (x, z, observed frame, metres).
        z_k : ndarray of shape (N,)
            Each state's conditional distance z (metres, observed frame).
        posterior : ndarray of shape (N,)
            The state posterior.
        speed : float
            The observed person's ground speed, m/s.

        Returns
        -------
        ndarray of shape (2 + 3 L + 4,)
            The placement, the label masses (L,), the motion summaries (4,), the labels' distances z
            (L,) and their differences to the placement's z (L,).
        """
        self._n_seen += 1
        self._speeds = (self._speeds + [speed])[-_SPEED_FRAMES:]
        mean_speed = float(np.mean(self._speeds))
        self._top_speed = max(self._top_speed, mean_speed)
        self._path += speed / self.fps
        member = self.label_member
        mass = member @ posterior
        z_l = (member @ (posterior * z_k)) / np.maximum(mass, 1e-12)
        motion = [
            min((self._n_seen - 1) / self.fps, _T_CAP_S),
            mean_speed,
            self._top_speed,
            min(self._path, _PATH_CAP_M),
        ]
        return np.concatenate([pos, mass, motion, z_l, z_l - pos[1]])


__all__ = ["ForestArrays", "CorrectionFeatures", "fit_forest", "deal_folds"]
