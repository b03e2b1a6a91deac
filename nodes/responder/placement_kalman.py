"""The partner's ground position kept in the world: a Kalman filter over the states' conditionals.

With the dual HMM's ``placement="tracked"`` the partner's ground position (x, z) is predicted with
the state-weighted conditional partner velocity and its covariance, and corrected with the
conditional placement and its covariance, both the moments of the state mixture. The partner keeps
walking or stepping back where the observed person gives no cue, and snaps to the observed person
where the state pins the position down (hands joined).
"""

from __future__ import annotations

import numpy as np

from .pair_features import ground_rot


def mixture_moments(w: np.ndarray, means: np.ndarray, covs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of a Gaussian mixture: m = sum_k w_k m_k, C = sum_k w_k (C_k + (m_k - m)
    (m_k - m)^T).

    Parameters
    ----------
    w : (N,) array
        The weights (sum 1).
    means : (N, D) array
        The components' means.
    covs : (N, D, D) array
        Their covariances.
    """
    m = w @ means
    C = np.einsum("n,nij->ij", w, covs) + np.einsum("n,ni,nj->ij", w, means - m, means - m)
    return m, C


class PlacementKalman:
    """Kalman filter of the partner's ground position (x, z) in the world, metres.

    Parameters
    ----------
    process_noise : float
        q, m^2 per frame added to the position variance (keeps the covariances invertible where the
        partner's placement is certain).
    fps : float
        Frames per second (the velocity is in m/s).
    """

    def __init__(self, process_noise: float, fps: float) -> None:
        self.process_noise, self.fps = float(process_noise), float(fps)
        self.reset()

    def reset(self) -> None:
        """Forget the track: the next measurement starts it."""
        self.state: tuple[np.ndarray, np.ndarray] | None = None  # position (2,) world, covariance (2, 2)

    def update(
        self,
        w: np.ndarray,
        m_k: np.ndarray,
        cov_pos: np.ndarray,
        v_k: np.ndarray,
        cov_vel: np.ndarray,
        origin: np.ndarray,
        theta: float,
    ) -> np.ndarray:
        """One frame: predict with the mixture's velocity, correct with its position.

        Parameters
        ----------
        w : (N,) array
            The state weights.
        m_k, cov_pos : (N, 2), (N, 2, 2) arrays
            Each state's conditional ground position (metres, observed frame) and its covariance.
        v_k, cov_vel : (N, 2), (N, 2, 2) arrays
            Each state's conditional ground velocity (m/s, observed frame) and its covariance.
        origin : (3,) array
            The observed person's frame origin, world metres.
        theta : float
            The observed person's heading, radians.

        Returns
        -------
        (2,) array
            The filtered position (x, z) in the observed frame, metres.
        """
        m, C = mixture_moments(w, m_k, cov_pos)
        v, Cv = mixture_moments(w, v_k, cov_vel)
        R = ground_rot(theta)
        g = origin[[0, 2]]
        meas, meas_cov = g + R @ m, R @ C @ R.T
        if self.state is None:
            pos, cov = meas, meas_cov
        else:
            pos, cov = self.state
            pos = pos + R @ v / self.fps
            cov = cov + R @ Cv @ R.T / self.fps**2 + self.process_noise * np.eye(2)
            K = cov @ np.linalg.inv(cov + meas_cov)
            pos = pos + K @ (meas - pos)
            cov = (np.eye(2) - K) @ cov
        self.state = (pos, 0.5 * (cov + cov.T))
        return R.T @ (pos - g)


__all__ = ["PlacementKalman", "mixture_moments"]
