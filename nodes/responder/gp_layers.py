"""Back-constrained sparse GP-LVM layers with a style factor, fitted with GPy, evaluated in numpy.

One layer maps a latent point x (q,) and an optional style vector s (n_s,) to data y (D,)::

    y = f(x, s) + e,   f ~ GP(0, k),   k([x, s], [x', s']) = k_RBF(x, x') (1 + s^T W s')     (1)

with k_RBF an ARD squared exponential and W = diag(w) >= 0 (Wang, Fleet & Hertzmann 2007's
multifactor kernel, the style factorisation of Taubert et al. 2013): f(x, s) = g_0(x) + sum_e s_e
g_e(x), a content function plus one function per style whose amount s_e is continuous. The
latent points are back-constrained (Lawrence & Quinonero-Candela 2006): x_n = g(y_n) =
sum_b A_b k_map(y_n, c_b) over B centres c_b drawn from the data, so that a new observation maps
to its latent point in one kernel evaluation (back-projection, no optimisation). Training
maximises the variational sparse bound of Titsias 2009 (GPy's VarDTC, M inducing inputs) over
A, the inducing inputs, the kernel parameters and the noise. GPy does the inference and the
gradients; this module adds only the back constraint over [x, s] with s fixed (GPy's BCGPLVM is
dense and has no fixed inputs) and the numpy evaluation of the fitted layer.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


def rbf(X: np.ndarray, Z: np.ndarray, lengthscale: np.ndarray | float, variance: float = 1.0) -> np.ndarray:
    """Squared-exponential kernel matrix.

    Parameters
    ----------
    X : ndarray of shape (N, d)
        First points.
    Z : ndarray of shape (M, d)
        Second points.
    lengthscale : ndarray of shape (d,) or float
        ARD lengthscales, or one for all dimensions.
    variance : float, default=1.0
        Kernel variance.

    Returns
    -------
    ndarray of shape (N, M)
        ``variance * exp(-0.5 |x - z|^2 / lengthscale^2)``.
    """
    A, B = X / lengthscale, Z / lengthscale
    d2 = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :] - 2.0 * A @ B.T
    return variance * np.exp(-0.5 * np.maximum(d2, 0.0))


@dataclass
class GPLayer:
    """A fitted layer (module docstring), all numpy.

    Attributes
    ----------
    y_mean, y_sd : ndarray of shape (D,)
        Data standardisation.
    centres : ndarray of shape (B, D)
        Back-constraint centres, standardised.
    map_ls : float
        The back-constraint kernel's lengthscale.
    A : ndarray of shape (B, q)
        The back-constraint kernel's weights.
    Z : ndarray of shape (M, q + n_s)
        Inducing inputs.
    ls : ndarray of shape (q,)
        The RBF's lengthscales.
    var : float
        The RBF's variance.
    style_w : ndarray of shape (n_s,)
        The style weights w.
    woodbury : ndarray of shape (M, D)
        The sparse posterior's weights (mean = K(x*, Z) woodbury).
    noise : float
        The Gaussian noise variance (standardised units).
    """

    y_mean: np.ndarray
    y_sd: np.ndarray
    centres: np.ndarray
    map_ls: float
    A: np.ndarray
    Z: np.ndarray
    ls: np.ndarray
    var: float
    style_w: np.ndarray
    woodbury: np.ndarray
    noise: float

    @property
    def q(self) -> int:
        return int(self.A.shape[1])

    def project(self, Y: np.ndarray) -> np.ndarray:
        """Back-projection of data to latent points.

        Parameters
        ----------
        Y : ndarray of shape (N, D)
            Data, data units.

        Returns
        -------
        ndarray of shape (N, q)
            Latent points.
        """
        Yn = (np.atleast_2d(Y) - self.y_mean) / self.y_sd
        return rbf(Yn, self.centres, self.map_ls) @ self.A

    def kernel(self, X: np.ndarray, S: np.ndarray | None = None) -> np.ndarray:
        """k([x, s], Z) of eq. (1).

        Parameters
        ----------
        X : ndarray of shape (N, q)
            Latent points.
        S : ndarray of shape (N, n_s) or None, default=None
            Style vectors (None: no style).

        Returns
        -------
        ndarray of shape (N, M)
            Kernel between the inputs and the inducing inputs.
        """
        q = self.q
        K = rbf(np.atleast_2d(X), self.Z[:, :q], self.ls, self.var)
        if len(self.style_w):
            S = np.zeros((len(K), len(self.style_w))) if S is None else np.atleast_2d(S)
            K = K * (1.0 + (S * self.style_w) @ self.Z[:, q:].T)
        return K

    def mean(self, X: np.ndarray, S: np.ndarray | None = None) -> np.ndarray:
        """Posterior mean of the data at latent points and styles.

        Parameters
        ----------
        X : ndarray of shape (N, q)
            Latent points.
        S : ndarray of shape (N, n_s) or None, default=None
            Style vectors (None: no style).

        Returns
        -------
        ndarray of shape (N, D)
            Posterior mean, data units.
        """
        return self.kernel(X, S) @ self.woodbury * self.y_sd + self.y_mean

    def arrays(self, prefix: str) -> dict[str, np.ndarray]:
        """The layer's fields as float64 arrays, for a model file.

        Parameters
        ----------
        prefix : str
            Prefix of the keys (``PREFIX_FIELD``).

        Returns
        -------
        dict of str to ndarray
            One entry per field.
        """
        return {f"{prefix}_{k}": np.asarray(v, np.float64) for k, v in self.__dict__.items()}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], prefix: str) -> GPLayer:
        """The layer from :meth:`arrays`' entries.

        Parameters
        ----------
        arrays : dict of str to ndarray
            Entries as :meth:`arrays` writes them (others are ignored).
        prefix : str
            Prefix of the keys.

        Returns
        -------
        GPLayer
            The layer.
        """
        kw: dict[str, Any] = {k: arrays[f"{prefix}_{k}"] for k in cls.__dataclass_fields__}
        for k in ("map_ls", "var", "noise"):
            kw[k] = float(kw[k])
        return cls(**kw)


def fit_layer(
    Y: np.ndarray,
    q: int,
    S: np.ndarray | None = None,
    num_inducing: int = 30,
    n_centres: int = 80,
    max_iters: int = 200,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    name: str = "layer",
) -> GPLayer:
    """Fit a back-constrained sparse GP-LVM layer (module docstring) with GPy.

    Each dimension is standardised, its scale floored at a tenth of the largest. The back
    constraint starts at the PCA projection (least squares), the inducing inputs at random data
    points.

    Parameters
    ----------
    Y : ndarray of shape (N, D)
        Data.
    q : int
        Latent dimensions.
    S : ndarray of shape (N, n_s) or None, default=None
        Fixed style amounts per point (None: no style).
    num_inducing : int, default=30
        Inducing inputs M.
    n_centres : int, default=80
        Back-constraint centres B.
    max_iters : int, default=200
        L-BFGS iterations.
    seed : int, default=0
        Seed of the centre and inducing-input choice.
    progress : callable or None, default=None
        Called with a line of progress text.
    name : str, default="layer"
        Name of the layer in progress text.

    Returns
    -------
    GPLayer
        The fitted layer.
    """
    import GPy

    rng = np.random.default_rng(seed)
    Y = np.asarray(Y, np.float64)
    N = len(Y)
    S = np.zeros((N, 0)) if S is None else np.asarray(S, np.float64)
    ns = S.shape[1]
    # standardised, but a dimension that barely moves (a relative heading that is always facing)
    # is not blown up into noise that the latent space would spend itself on
    sd = Y.std(0)
    y_mean, y_sd = Y.mean(0), np.maximum(sd, max(0.1 * float(sd.max()), 1e-6))
    Yn = (Y - y_mean) / y_sd
    # PCA start for the latent points, scaled to unit variance per dimension
    U, sv, _ = np.linalg.svd(Yn - Yn.mean(0), full_matrices=False)
    X0 = U[:, :q] * np.sqrt(N)
    centres = Yn[rng.choice(N, size=min(n_centres, N), replace=False)]
    d2 = ((centres[:, None] - centres[None]) ** 2).sum(-1)
    map_ls = float(np.sqrt(np.median(d2[d2 > 0]))) if (d2 > 0).any() else 1.0
    Kc = rbf(Yn, centres, map_ls)
    A0 = np.linalg.solve(Kc.T @ Kc + 1e-3 * np.eye(len(centres)), Kc.T @ X0)

    D = Yn.shape[1]
    mapping = GPy.mappings.Kernel(D, q, centres, GPy.kern.RBF(D, lengthscale=map_ls))
    mapping.A[:] = A0
    kern = GPy.kern.RBF(q, ARD=True, active_dims=list(range(q)))
    if ns:
        sd = list(range(q, q + ns))
        bias = GPy.kern.Bias(ns, variance=1.0, active_dims=sd)
        bias.variance.fix()  # the content term's scale is the RBF's variance
        kern = kern * (bias + GPy.kern.Linear(ns, ARD=True, active_dims=sd))
    X = np.hstack([X0, S])
    Z = X[rng.choice(N, size=min(num_inducing, N), replace=False)].copy()
    model = _bc_class()(Yn, S, mapping, kern, Z)
    model.likelihood.variance = 0.05
    say = progress or (lambda s: None)
    say(
        f"{name}: back-constrained sparse GP-LVM, {N} points x {D} dims -> {q} latent"
        f"{f' + {ns} style' if ns else ''}, {len(Z)} inducing, up to {max_iters} iterations"
    )
    t0 = time.perf_counter()
    model.optimize("lbfgsb", max_iters=max_iters, messages=False)
    say(f"{name}: {time.perf_counter() - t0:.1f} s, bound {-float(model.objective_function()):.1f}")
    post = model.posterior
    if ns:
        rbf_k, lin = model.kern.parts[0], model.kern.parts[1].parts[1]
        style_w = np.asarray(lin.variances, np.float64).copy()
    else:
        rbf_k, style_w = model.kern, np.zeros(0)
    return GPLayer(
        y_mean=y_mean,
        y_sd=y_sd,
        centres=centres,
        map_ls=map_ls,
        A=np.asarray(mapping.A).copy(),
        Z=np.asarray(model.Z).copy(),
        ls=np.asarray(rbf_k.lengthscale, np.float64).copy() * np.ones(q),
        var=float(np.ravel(rbf_k.variance)[0]),
        style_w=style_w,
        woodbury=np.asarray(post.woodbury_vector).copy(),
        noise=float(np.ravel(model.likelihood.variance)[0]),
    )


_BC: type | None = None


def _bc_class() -> type:
    """GPy's sparse GP with the latent inputs back-constrained and the style inputs fixed (built on
    first use so that GPy is imported only for training).
    """
    global _BC
    if _BC is not None:
        return _BC
    import GPy
    from GPy.core import SparseGP
    from GPy.inference.latent_function_inference import VarDTC

    class BCSparseGPLVM(SparseGP):
        def __init__(self, Y: np.ndarray, S: np.ndarray, mapping: Any, kernel: Any, Z: np.ndarray) -> None:
            self.S, self.mapping = S, mapping
            super().__init__(
                np.hstack([mapping.f(Y), S]),
                Y,
                Z,
                kernel,
                GPy.likelihoods.Gaussian(),
                inference_method=VarDTC(),
                name="bc_sparse_gplvm",
            )
            self.link_parameter(self.mapping)

        def parameters_changed(self) -> None:
            self.X = np.hstack([self.mapping.f(self.Y), self.S])
            super().parameters_changed()
            g = self.kern.gradients_X_diag(self.grad_dict["dL_dKdiag"], self.X)
            g = g + self.kern.gradients_X(self.grad_dict["dL_dKnm"], self.X, self.Z)
            self.mapping.update_gradients(g[:, : self.mapping.output_dim], self.Y)

    _BC = BCSparseGPLVM
    return _BC
