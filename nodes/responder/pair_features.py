"""The dual HMM's features: both people of a pair as one vector per frame (Zheng et al. 2006).

Both people are expressed in the observed person's actor-centred frame
(:mod:`counterpart.nodes.responder.frames`), so the features do not depend on where the pair
stands. Each person's own pose (14 joints x 3 = 42 numbers, in their own actor frame) is reduced by
its own whitened PCA. The observed block o_t is the observed person's PCA pose plus their ground
velocity in their own frame (3 numbers, m/s, scaled by ``velocity_weight``). The partner block p_t
is the partner's placement in the observed frame (ground position x, z in metres; cos, sin of the
relative heading), the partner's ground velocity (x, z, m/s, observed frame), all standardised, and
the partner's PCA pose. A frame of training is x_t = [o_t, p_t].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from counterpart.body.trajectory import TwoPersonTrajectory

from .frames import actor_frame, to_local, to_world

#: the partner block starts with NQ placement numbers: placement x, z (metres), cos, sin of the
#: relative heading, ground velocity x, z (m/s), all in the observed frame; then the partner's PCA
NQ = 6
#: where the ground position (metres) and the ground velocity (m/s) lie in the placement numbers
POS, VEL = np.array([0, 1]), np.array([4, 5])


class WhitenedPCA:
    """A fitted whitened PCA as plain arrays: z = (x - mean) C^T / scale, x = mean + (z scale) C.

    Parameters
    ----------
    mean : ndarray of shape (D,)
        The training mean.
    components : ndarray of shape (d, D)
        The principal axes C.
    scale : ndarray of shape (d,)
        The standard deviation along each axis (the whitening).
    """

    def __init__(self, mean: np.ndarray, components: np.ndarray, scale: np.ndarray) -> None:
        self.mean, self.components, self.scale = mean, components, scale

    @classmethod
    def fit(cls, X: np.ndarray, energy: float) -> WhitenedPCA:
        """The whitened PCA of samples.

        Parameters
        ----------
        X : ndarray of shape (T, D)
            Samples.
        energy : float
            The fraction of the variance kept, in (0, 1).

        Returns
        -------
        WhitenedPCA
            The fitted PCA.
        """
        from sklearn.decomposition import PCA  # here: a loaded model needs only its arrays; sklearn is slow to import

        p = PCA(energy, whiten=True, svd_solver="full").fit(X)
        return cls(p.mean_, p.components_, np.sqrt(p.explained_variance_))

    def forward(self, x: np.ndarray) -> np.ndarray:
        """Samples to whitened coordinates.

        Parameters
        ----------
        x : ndarray of shape (T, D)
            Samples.

        Returns
        -------
        ndarray of shape (T, d)
            Whitened coordinates.
        """
        return ((x - self.mean) @ self.components.T) / self.scale

    def inverse(self, z: np.ndarray) -> np.ndarray:
        """Whitened coordinates back to samples.

        Parameters
        ----------
        z : ndarray of shape (T, d) or (d,)
            Whitened coordinates.

        Returns
        -------
        ndarray of shape (T, D) or (D,)
            Samples.
        """
        return self.mean + (z * self.scale) @ self.components

    def arrays(self, tag: str) -> dict[str, np.ndarray]:
        """The arrays of a model file.

        Parameters
        ----------
        tag : str
            Prefix of the names.

        Returns
        -------
        dict of str to ndarray
            ``{tag}_mean``, ``{tag}_components``, ``{tag}_scale``.
        """
        return {f"{tag}_mean": self.mean, f"{tag}_components": self.components, f"{tag}_scale": self.scale}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], tag: str) -> WhitenedPCA:
        """The inverse of :meth:`arrays`.

        Parameters
        ----------
        arrays : dict of str to ndarray
            The arrays of a model file.
        tag : str
            Prefix of the names.

        Returns
        -------
        WhitenedPCA
            The PCA.
        """
        return cls(arrays[f"{tag}_mean"], arrays[f"{tag}_components"], arrays[f"{tag}_scale"])


def partner_placement(partner: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The partner relative to the observed frame.

    Parameters
    ----------
    partner : ndarray of shape (T, 14, 3)
        The partner's joints, metres, world frame.
    origin : ndarray of shape (T, 3)
        The observed frame's origin, metres.
    theta : ndarray of shape (T,)
        The observed frame's heading, radians.

    Returns
    -------
    placement : ndarray of shape (T, 4)
        The partner frame's origin x, z in the observed frame (metres) and cos, sin of the relative heading.
    own : ndarray of shape (T, 14, 3)
        The partner's pose in their own frame, metres.
    """
    po, pth = actor_frame(partner)
    rel_o = to_local(po[:, None, :], origin, theta)[:, 0]
    d = pth - theta
    return np.stack([rel_o[:, 0], rel_o[:, 2], np.cos(d), np.sin(d)], axis=1), to_local(partner, po, pth)


def partner_velocity(partner: np.ndarray, theta: np.ndarray, fps: float) -> np.ndarray:
    """The partner's ground velocity in the observed frame.

    A backward difference, v_t = (r_t - r_{t-1}) fps (v_0 = 0), so that r_t = r_{t-1} + v_t / fps
    integrates it exactly.

    Parameters
    ----------
    partner : ndarray of shape (T, 14, 3)
        The partner's joints, metres, world frame.
    theta : ndarray of shape (T,)
        The observed frame's heading, radians.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray of shape (T, 2)
        Velocity x, z, m/s.
    """
    po, _ = actor_frame(partner)
    d = np.diff(po, axis=0, prepend=po[:1]) * fps
    return to_local(d[:, None, :], np.zeros_like(po), theta)[:, 0][:, [0, 2]]


def own_velocity(observed: np.ndarray, fps: float) -> np.ndarray:
    """Ground velocity of a person's frame origin in their own frame.

    Parameters
    ----------
    observed : ndarray of shape (T, 14, 3)
        Joints, metres, world frame.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray of shape (T, 3)
        Velocity, m/s (backward difference, the first frame 0).
    """
    o, th = actor_frame(observed)
    d = np.diff(o, axis=0, prepend=o[:1]) * fps
    return to_local(d[:, None, :], np.zeros_like(o), th)[:, 0]


def ground_rot(theta: float) -> np.ndarray:
    """Rotation of ground vectors (x, z) from a frame to the world.

    Parameters
    ----------
    theta : float
        The frame's heading, radians.

    Returns
    -------
    ndarray of shape (2, 2)
        The rotation.
    """
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, s], [-s, c]])


def partner_world(q: np.ndarray, own: np.ndarray, origin: np.ndarray, theta: float) -> np.ndarray:
    """The partner's world joints from their placement and own-frame pose.

    Parameters
    ----------
    q : ndarray of shape (4,) or more
        Placement x, z (metres) and cos, sin of the relative heading, in the observed frame.
    own : ndarray of shape (14, 3)
        The partner's joints in their own frame, metres.
    origin : ndarray of shape (3,)
        The observed frame's origin, metres.
    theta : float
        The observed frame's heading, radians.

    Returns
    -------
    ndarray of shape (14, 3)
        The partner's world joints, metres.
    """
    p_origin = to_world(np.array([[q[0], 0.0, q[1]]]), origin, theta)[0]
    return to_world(own, p_origin, theta + np.arctan2(q[3], q[2]))


@dataclass
class RolePair:
    """One training sequence seen from one role: the observed person and the partner.

    Attributes
    ----------
    local : ndarray of shape (T, 14, 3)
        The observed person's pose in their own actor frame, metres.
    velocity : ndarray of shape (T, 3)
        The observed person's ground velocity in their own frame, m/s.
    placement : ndarray of shape (T, 4)
        The partner's placement in the observed frame (x, z metres; cos, sin of the relative heading).
    partner_velocity : ndarray of shape (T, 2)
        The partner's ground velocity in the observed frame, m/s.
    own : ndarray of shape (T, 14, 3)
        The partner's pose in their own actor frame, metres.
    label : str
        The interaction.
    phase : ndarray of shape (T,) or None
        The phase labels of the frames, where the trajectory has them.
    """

    local: np.ndarray
    velocity: np.ndarray
    placement: np.ndarray
    partner_velocity: np.ndarray
    own: np.ndarray
    label: str
    phase: np.ndarray | None


def role_pairs(trajectories: Sequence[TwoPersonTrajectory], both_roles: bool) -> list[RolePair]:
    """Each trajectory as A observed / B partner, and also B observed / A partner.

    Parameters
    ----------
    trajectories : sequence of TwoPersonTrajectory
        Training trajectories.
    both_roles : bool
        Also take B as the observed person.

    Returns
    -------
    list of RolePair
        One per trajectory and role, in order.
    """
    out = []
    for t in trajectories:
        roles = [(t.a, t.b), (t.b, t.a)] if both_roles else [(t.a, t.b)]
        for obs, par in roles:
            o, th = actor_frame(obs)
            q, own = partner_placement(par, o, th)
            out.append(
                RolePair(
                    to_local(obs, o, th),
                    own_velocity(obs, t.fps),
                    q,
                    partner_velocity(par, th, t.fps),
                    own,
                    t.label,
                    t.phase,
                )
            )
    return out


class PairEncoder:
    """The map between two people and the HMM's vectors x = [o, p] (module docstring).

    Parameters
    ----------
    pca_o, pca_p : WhitenedPCA
        The observed person's and the partner's own-pose PCA (42 -> d numbers).
    place_mean, place_scale : ndarray of shape (NQ,)
        The standardisation of the partner's placement and ground velocity.
    velocity_weight : float
        Scale of the observed ground velocity (m/s) in the observed block (0 drops it).
    """

    def __init__(
        self,
        pca_o: WhitenedPCA,
        pca_p: WhitenedPCA,
        place_mean: np.ndarray,
        place_scale: np.ndarray,
        velocity_weight: float,
    ) -> None:
        self.pca_o, self.pca_p = pca_o, pca_p
        self.place_mean, self.place_scale = place_mean, place_scale
        self.velocity_weight = float(velocity_weight)

    @classmethod
    def fit(cls, pairs: Sequence[RolePair], energy: float, velocity_weight: float) -> PairEncoder:
        """Fit both PCAs and the standardisation of the placement numbers to training pairs.

        Parameters
        ----------
        pairs : sequence of RolePair
            Training pairs.
        energy : float
            The fraction of each person's pose variance the PCAs keep.
        velocity_weight : float
            Scale of the observed ground velocity (m/s) in the observed block (0 drops it).

        Returns
        -------
        PairEncoder
            The fitted encoder.
        """
        O, _, Q, P = _stack(pairs)
        # the placement (metres, cos/sin of the relative heading) and the partner's ground velocity
        # (m/s) are standardised like a whitened PCA block
        return cls(
            WhitenedPCA.fit(O, energy),
            WhitenedPCA.fit(P, energy),
            Q.mean(0),
            np.maximum(Q.std(0), 1e-3),
            velocity_weight,
        )

    @property
    def d_o(self) -> int:
        """Numbers in the observed block."""
        return len(self.pca_o.scale) + (3 if self.velocity_weight > 0 else 0)

    def observed(self, local: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """The observed block of frames.

        Parameters
        ----------
        local : ndarray of shape (T, 14, 3)
            The observed person's pose in their own frame, metres.
        velocity : ndarray of shape (T, 3)
            Their ground velocity, m/s.

        Returns
        -------
        ndarray of shape (T, d_o)
            The observed block.
        """
        z = self.pca_o.forward(local.reshape(len(local), -1))
        if self.velocity_weight > 0:
            z = np.concatenate([z, velocity * self.velocity_weight], axis=1)
        return z

    def encode(self, pairs: Sequence[RolePair]) -> np.ndarray:
        """The frames x = [o, p] of training pairs, in the pairs' order.

        Parameters
        ----------
        pairs : sequence of RolePair
            Training pairs.

        Returns
        -------
        ndarray of shape (sum T, d)
            Their frames.
        """
        O, V, Q, P = _stack(pairs)
        return np.concatenate(
            [
                self.observed(O.reshape(-1, 14, 3), V),
                (Q - self.place_mean) / self.place_scale,
                self.pca_p.forward(P),
            ],
            axis=1,
        )

    def placement(self, zq: np.ndarray) -> np.ndarray:
        """Standardised placement numbers back to their units.

        Parameters
        ----------
        zq : ndarray of shape (..., NQ)
            Standardised placement numbers.

        Returns
        -------
        ndarray of shape (..., NQ)
            Metres, cos/sin and m/s.
        """
        return zq * self.place_scale + self.place_mean

    def partner(self, q: np.ndarray, zp: np.ndarray, origin: np.ndarray, theta: float) -> np.ndarray:
        """The partner's world joints from their placement and PCA pose.

        Parameters
        ----------
        q : ndarray of shape (4,) or more
            Placement x, z (metres) and cos, sin of the relative heading, in the observed frame.
        zp : ndarray of shape (d_p,)
            The partner's PCA pose.
        origin : ndarray of shape (3,)
            The observed frame's origin, metres.
        theta : float
            The observed frame's heading, radians.

        Returns
        -------
        ndarray of shape (14, 3)
            The partner's world joints, metres.
        """
        return partner_world(q, self.pca_p.inverse(zp).reshape(14, 3), origin, theta)

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays of a model file.

        Returns
        -------
        dict of str to ndarray
            The PCAs' arrays (``pca_o_*``, ``pca_p_*``), ``place_mean`` and ``place_scale``.
        """
        return {
            **self.pca_o.arrays("pca_o"),
            **self.pca_p.arrays("pca_p"),
            "place_mean": self.place_mean,
            "place_scale": self.place_scale,
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], velocity_weight: float) -> PairEncoder:
        """The inverse of :meth:`arrays`.

        Parameters
        ----------
        arrays : dict of str to ndarray
            The arrays of a model file.
        velocity_weight : float
            Scale of the observed ground velocity (m/s) in the observed block (0 drops it).

        Returns
        -------
        PairEncoder
            The encoder.
        """
        return cls(
            WhitenedPCA.from_arrays(arrays, "pca_o"),
            WhitenedPCA.from_arrays(arrays, "pca_p"),
            arrays["place_mean"],
            arrays["place_scale"],
            velocity_weight,
        )


def _stack(pairs: Sequence[RolePair]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Training pairs -> observed poses (sum T, 42), velocities (sum T, 3), placement numbers
    (sum T, NQ), partner poses (sum T, 42).
    """
    O = np.concatenate([p.local for p in pairs]).reshape(-1, 42)
    V = np.concatenate([p.velocity for p in pairs])
    Q = np.concatenate([np.concatenate([p.placement, p.partner_velocity], axis=1) for p in pairs])
    P = np.concatenate([p.own for p in pairs]).reshape(-1, 42)
    return O, V, Q, P


__all__ = [
    "NQ",
    "POS",
    "VEL",
    "WhitenedPCA",
    "PairEncoder",
    "RolePair",
    "role_pairs",
    "partner_placement",
    "partner_velocity",
    "own_velocity",
    "ground_rot",
    "partner_world",
]
