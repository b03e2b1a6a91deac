"""Fitting the dual HMM's states: one Gaussian HMM block per interaction label, joined into one.

The states are fitted per interaction label (``TwoPersonTrajectory.label``): Baum-Welch (hmmlearn,
full covariances) on each label's sequences with its share of the N states, in proportion to the
label's number of phases (a three-phase interaction gets three times the states of a
conversation). Where the label's trajectories carry phase labels with more than one phase
(approach, contact, retreat), Baum-Welch starts from a time-ordered model (:func:`init_ordered`):
the states are shared out between the phases and along time within each phase, the first state is
the start and the transitions run forward (mixed with ``order_mix`` of uniform). The states then
follow the interaction's course, so the standing of the start (partner far away, about to walk in)
and the standing of the end (partner still, after stepping back) are different states. Other
labels (one phase all through, e.g. a conversation, or no phase labels) start from hmmlearn's
k-means initialisation. The blocks are joined into the one HMM (:func:`join_blocks`) with a
block-diagonal A, start probabilities weighted by each label's share of the data and a small
``leak`` towards the start distribution so that a change of interaction is followed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class HMMParams:
    """The joined HMM, in the encoded units.

    Parameters
    ----------
    startprob : ndarray of shape (N,)
        Start probabilities.
    transmat : ndarray of shape (N, N)
        Transition matrix.
    means : ndarray of shape (N, d)
        State means.
    covars : ndarray of shape (N, d, d)
        State covariances.
    block_labels : ndarray of shape (N,)
        The interaction label of each state.
    """

    startprob: np.ndarray
    transmat: np.ndarray
    means: np.ndarray
    covars: np.ndarray
    block_labels: np.ndarray


@dataclass(frozen=True)
class Block:
    """One interaction label's fitted HMM and its share of the training sequences.

    Parameters
    ----------
    label : str
        The interaction label.
    hmm : hmmlearn GaussianHMM
        The fitted model.
    weight : float
        The label's share of the training sequences.
    """

    label: str
    hmm: Any
    weight: float


def new_hmm(n: int, d: int, n_iter: int, min_covar: float, random_state: int, ordered: bool) -> Any:
    """An unfitted hmmlearn ``GaussianHMM`` of ``n`` states over ``d`` numbers, full covariances.

    Parameters
    ----------
    n : int
        States.
    d : int
        Dimensions of the encoded frames.
    n_iter : int
        Baum-Welch iterations at most.
    min_covar : float
        Floor on the covariances' diagonal, also the ridge of the covariance prior.
    random_state : int
        Seed.
    ordered : bool
        True: the caller sets the start (:func:`init_ordered`); False: hmmlearn's k-means start.

    Returns
    -------
    hmmlearn GaussianHMM
        The unfitted model.
    """
    from counterpart.body.gaussian_hmm import full_gaussian_hmm

    # the priors (a ridge of one pseudo-frame, a vanishing pull of the means to 0) keep the
    # M-step finite and positive definite for a state that Baum-Welch leaves (almost) empty
    return full_gaussian_hmm(
        n_components=n,
        n_iter=n_iter,
        min_covar=min_covar,
        covars_prior=min_covar * np.eye(d),
        covars_weight=d + 1,
        means_weight=1e-3,
        random_state=random_state,
        tol=1e-3,
        init_params="" if ordered else "stmc",
    )


def init_ordered(
    hmm: Any, seqs: list[np.ndarray], phases: list[np.ndarray], order_mix: float, min_covar: float
) -> None:
    """Time-ordered start for one block: the states are shared out between the interaction's
    phases in proportion to their frames, and within a phase each sequence's frames are cut into
    equal time segments; state k's Gaussian is fitted to its segments (plus ``min_covar`` on the
    diagonal). Start in the first state, stay or move one state on (A banded), both mixed with
    ``order_mix`` of uniform so that Baum-Welch can still learn other transitions.

    Parameters
    ----------
    hmm : hmmlearn GaussianHMM
        The block's model (``n_components`` states); its means, covariances, transitions and start
        probabilities are set.
    seqs : list of ndarray of shape (T_i, d)
        The block's sequences.
    phases : list of ndarray of shape (T_i,)
        Their frames' phase labels.
    order_mix : float
        Share of uniform mixed into the banded transitions and the start, in [0, 1].
    min_covar : float
        Added to the covariances' diagonal.
    """
    n, d = hmm.n_components, seqs[0].shape[1]
    names = sorted(set(np.concatenate(phases).tolist()))
    counts = np.array([sum(int((ph == p).sum()) for ph in phases) for p in names], float)
    share = np.maximum(1, np.floor(n * counts / counts.sum())).astype(int)
    while share.sum() < n:
        share[np.argmax(n * counts / counts.sum() - share)] += 1
    while share.sum() > n:
        share[np.argmax(share)] -= 1
    first = np.cumsum(share) - share
    assign = []
    for ph in phases:
        a = np.zeros(len(ph), int)
        for p, f, c in zip(names, first, share):
            idx = np.flatnonzero(ph == p)
            a[idx] = f + (np.arange(len(idx)) * c) // max(len(idx), 1)
        assign.append(a)
    Xc, ac = np.concatenate(seqs), np.concatenate(assign)
    means, covars = np.zeros((n, d)), np.zeros((n, d, d))
    for k in range(n):
        sk = Xc[ac == k] if (ac == k).sum() > d else Xc
        means[k], covars[k] = sk.mean(0), np.cov(sk.T) + min_covar * np.eye(d)
    stay = 1.0 - n / np.mean([len(x) for x in seqs])
    A = np.eye(n) * stay + np.eye(n, k=1) * (1 - stay)
    A[-1, -1] = 1.0
    hmm.means_, hmm.covars_ = means, covars
    hmm.transmat_ = (1 - order_mix) * A + order_mix / n
    hmm.startprob_ = (1 - order_mix) * np.eye(n)[0] + order_mix / n


def phase_counts(labels: Sequence[str], phases: Sequence[np.ndarray | None]) -> dict[str, int]:
    """Each label's number of phases: the distinct phase labels of its sequences (one where any
    of them has none).

    Parameters
    ----------
    labels : sequence of str
        Each sequence's interaction label.
    phases : sequence of ndarray or None
        Each sequence's frames' phase labels, or None.

    Returns
    -------
    dict of str to int
        Label -> number of phases.
    """
    out = {}
    for g in sorted(set(labels)):
        ph = [p for lab, p in zip(labels, phases) if lab == g]
        out[g] = 1 if any(p is None for p in ph) else len(np.unique(np.concatenate(ph)))
    return out


def fit_blocks(
    X: np.ndarray,
    lengths: np.ndarray,
    labels: Sequence[str],
    phases: Sequence[np.ndarray | None],
    n_states: int,
    n_iter: int,
    order_mix: float,
    min_covar: float,
    random_state: int,
) -> list[Block]:
    """Baum-Welch per interaction label (module docstring).

    Parameters
    ----------
    X : ndarray of shape (sum T, d)
        The encoded frames of all sequences, one after the other.
    lengths : ndarray of shape (S,), dtype int
        The sequences' frame counts.
    labels, phases : sequences of S
        Each sequence's interaction label and its frames' phase labels (or None).
    n_states, n_iter, order_mix, min_covar, random_state
        As :class:`~counterpart.nodes.responder.dual_hmm.FitConfig`.

    Returns
    -------
    list of Block
        One per label, in sorted label order.
    """
    import logging

    logging.getLogger("hmmlearn").setLevel(logging.ERROR)  # EM wobble warnings are not actionable
    n_phases = phase_counts(labels, phases)
    total = sum(n_phases.values())
    starts, ends = np.cumsum(lengths) - lengths, np.cumsum(lengths)
    blocks = []
    for g in sorted(n_phases):
        idx = [i for i, lab in enumerate(labels) if lab == g]
        seqs = [X[starts[i] : ends[i]] for i in idx]
        Xg = np.concatenate(seqs)
        # the state budget is shared out by phases: a three-phase interaction gets three times
        # the states of a one-phase one (a conversation)
        n = min(max(2, n_states * n_phases[g] // total), len(Xg))
        ordered = order_mix < 1 and n_phases[g] > 1
        hmm = new_hmm(n, X.shape[1], n_iter, min_covar, random_state, ordered)
        if ordered:
            init_ordered(hmm, seqs, [phases[i] for i in idx], order_mix, min_covar)
        hmm.fit(Xg, lengths[idx])
        blocks.append(Block(g, hmm, len(idx) / len(labels)))
    return blocks


def join_blocks(blocks: Sequence[Block], min_covar: float, leak: float) -> HMMParams:
    """One HMM from the labels' blocks: block-diagonal transitions (one block per interaction
    type), start probabilities weighted by the blocks' shares, and (more than one block) a
    ``leak`` towards the start distribution so that a changed interaction is picked up.

    Parameters
    ----------
    blocks : sequence of Block
        The labels' fitted blocks.
    min_covar : float
        Ridge added to every state's covariance so that each stays invertible.
    leak : float
        Share of the transitions towards the start distribution (more than one block), in [0, 1].

    Returns
    -------
    HMMParams
        The joined HMM, rows normalised.
    """
    N = sum(b.hmm.n_components for b in blocks)
    A = np.zeros((N, N))
    pi, means, covars = np.zeros(N), [], []
    k = 0
    for b in blocks:
        hmm, n = b.hmm, b.hmm.n_components
        # a state that Baum-Welch left empty has no transitions out (a zero row): it stays
        T = np.nan_to_num(hmm.transmat_)
        empty = T.sum(1) <= 0
        T[empty] = np.eye(n)[empty]
        A[k : k + n, k : k + n] = T
        pi[k : k + n] = b.weight * hmm.startprob_
        means.append(np.nan_to_num(hmm.means_))
        # states that collapsed onto a few frames (e.g. standing still: zero velocity) get a ridge
        # so that every S_oo,k stays invertible
        covars.append(hmm.covars_ + min_covar * np.eye(hmm.means_.shape[1]))
        k += n
    if len(blocks) > 1:
        A = (1 - leak) * A + leak * np.broadcast_to(pi, A.shape)
    return HMMParams(
        pi / pi.sum(),
        A / A.sum(1, keepdims=True),
        np.concatenate(means),
        np.concatenate(covars),
        np.repeat([b.label for b in blocks], [b.hmm.n_components for b in blocks]),
    )


__all__ = ["HMMParams", "Block", "new_hmm", "init_ordered", "phase_counts", "fit_blocks", "join_blocks"]
