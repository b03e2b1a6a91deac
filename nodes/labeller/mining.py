"""Association rules between a speaker's signals and a listener's response (Okwechime et al.,
Sec. "Rule mining": Apriori over transactions with temporal bagging).

Transactions (one per speaker frame ``t``)::

    T_t = { "S:<x>" : speaker signal x present at frame t }
        U { "L:<y>" : listener signal y present at ANY frame of [t+s-b, t+s+b] }

``s`` is the response offset (``offset``, frames; default 10 = 0.4 s at 25 fps) and ``b`` the
half-width of the temporal bag (``bag``, frames; default 0 = exactly frame ``t+s``). Bagging lets a
response that comes a little earlier or later than ``s`` still count. Frames ``t`` whose bag
leaves the recording are dropped, so a recording of ``T`` frames gives ``T - s - b`` transactions
(fewer if ``b > s``); recordings are bagged separately and then pooled, so no bag spans two files.
Frames with no signal at all stay in as empty transactions: they are part of the support's
denominator. UNKNOWN labels count as "not present" (see :func:`~counterpart.nodes.labeller.signals.labels_to_bool`).

Frequent itemsets come from mlxtend's ``apriori`` and rules from ``association_rules``; only rules
whose antecedent is all speaker items and whose consequent is all listener items are kept, with::

    support    = P(A and C),  confidence = P(C | A) = support / P(A),  lift = confidence / P(C)

For two scenarios (interested / not-interested listener) :func:`compare_scenarios` pairs the same
rule in both and gives the ratio of their confidences (Okwechime et al., Table 2).
"""

from __future__ import annotations

import csv
import inspect
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from mlxtend.frequent_patterns import apriori, association_rules, fpgrowth
from numpy.lib.stride_tricks import sliding_window_view

from counterpart.nodes.labeller.signals import UNKNOWN, labels_to_bool

SPEAKER_PREFIX = "S:"
LISTENER_PREFIX = "L:"

RULES_FORMAT = "counterpart.labeller.rules"
RULES_VERSION = 1


def _as_json(rule: Any) -> dict[str, Any]:
    """A rule-like dataclass as JSON-able dict (item tuples as lists)."""
    d = asdict(rule)
    d["antecedent"], d["consequent"] = list(rule.antecedent), list(rule.consequent)
    return d


@dataclass(frozen=True)
class Rule:
    """One association rule ``antecedent -> consequent``.

    Parameters
    ----------
    antecedent : tuple of str
        Speaker items "S:<signal>", sorted.
    consequent : tuple of str
        Listener items "L:<signal>", sorted.
    support : float
        P(A and C), fraction of transactions.
    confidence : float
        P(C | A).
    lift : float
        confidence / P(C).
    antecedent_support : float
        P(A), fraction of transactions.
    consequent_support : float
        P(C), fraction of transactions.
    """

    antecedent: tuple[str, ...]
    consequent: tuple[str, ...]
    support: float
    confidence: float
    lift: float
    antecedent_support: float
    consequent_support: float

    @property
    def key(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """(antecedent, consequent): the rule whatever its figures."""
        return self.antecedent, self.consequent

    def __str__(self) -> str:
        return (
            f"{{{', '.join(self.antecedent)}}} -> {{{', '.join(self.consequent)}}} "
            f"(support {self.support:.3f}, confidence {self.confidence:.3f}, lift {self.lift:.2f})"
        )

    def to_dict(self) -> dict[str, Any]:
        """The rule as a JSON-able dict (item tuples as lists).

        Returns
        -------
        dict of str to object
            Every field by name.
        """
        return _as_json(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Rule:
        """The inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : mapping of str to object
            Every field by name.

        Returns
        -------
        Rule
            The rule.
        """
        return cls(
            antecedent=tuple(d["antecedent"]),
            consequent=tuple(d["consequent"]),
            support=float(d["support"]),
            confidence=float(d["confidence"]),
            lift=float(d["lift"]),
            antecedent_support=float(d["antecedent_support"]),
            consequent_support=float(d["consequent_support"]),
        )


def _as_bool(labels: np.ndarray, what: str) -> np.ndarray:
    a = np.asarray(labels)
    if a.ndim != 2:
        raise ValueError(f"{what} must be (T,K) labels (bool, or 1/0/{UNKNOWN}), got shape {a.shape}")
    return labels_to_bool(a)


def build_transactions(
    speaker_labels: np.ndarray,
    listener_labels: np.ndarray,
    names: Sequence[str],
    offset: int = 10,
    bag: int = 0,
    listener_names: Sequence[str] | None = None,
    speaker_mask: np.ndarray | None = None,
) -> pd.DataFrame:
    """One-hot transactions (rows: speaker frames; columns "S:<name>" then "L:<name>"), bool.

    See the module docstring for the bagging.

    Parameters
    ----------
    speaker_labels : ndarray of shape (T, K)
        The speaker's labels, bool (or 1/0/UNKNOWN int).
    listener_labels : ndarray of shape (T, K')
        The listener's labels of the same recording (same clock).
    names : sequence of str, length K
        The speaker signal names (also the listener's unless ``listener_names``).
    offset : int, default=10
        s, frames (>= 0).
    bag : int, default=0
        b, frames (>= 0).
    listener_names : sequence of str or None, default=None
        The K' listener signal names; None for ``names``.
    speaker_mask : ndarray of shape (T,), dtype bool, or None, default=None
        Keep only the frames ``t`` where it is True, e.g. the frames where this person holds the
        turn in a conversation whose speaker and listener swap roles (:func:`turn_transactions`);
        the listener's bag may still reach past the mask.

    Returns
    -------
    pandas.DataFrame
        One bool row per kept speaker frame, columns "S:<name>" then "L:<name>".

    Raises
    ------
    ValueError
        Labels not 2D, streams of different lengths, names that do not match the columns or are not
        unique, a negative offset or bag, or a mask of the wrong shape.
    """
    sp = _as_bool(speaker_labels, "speaker_labels")
    li = _as_bool(listener_labels, "listener_labels")
    lnames = list(names if listener_names is None else listener_names)
    if sp.shape[0] != li.shape[0]:
        raise ValueError(
            f"speaker and listener label streams must have the same number of frames "
            f"(one clock), got {sp.shape[0]} and {li.shape[0]}"
        )
    if sp.shape[1] != len(names) or li.shape[1] != len(lnames):
        raise ValueError(
            f"names do not match the label columns: {len(names)} speaker names for "
            f"{sp.shape[1]} columns, {len(lnames)} listener names for {li.shape[1]}"
        )
    if offset < 0 or bag < 0:
        raise ValueError(f"offset and bag must be >= 0 frames, got offset={offset}, bag={bag}")
    t = sp.shape[0]
    first = max(0, bag - offset)  # first t whose bag starts inside the recording
    last = t - 1 - offset - bag  # last t whose bag ends inside it
    n = max(0, last - first + 1)
    lo = first + offset - bag
    if n == 0:
        lb = np.zeros((0, li.shape[1]), dtype=bool)
    elif bag == 0:
        lb = li[lo : lo + n]
    else:
        lb = sliding_window_view(li[lo : lo + n + 2 * bag], 2 * bag + 1, axis=0).any(axis=-1)
    cols = [SPEAKER_PREFIX + x for x in names] + [LISTENER_PREFIX + y for y in lnames]
    if len(set(cols)) != len(cols):
        raise ValueError(f"signal names must be unique, got {list(names)} / {lnames}")
    data = np.concatenate([sp[first : first + n], lb], axis=1)
    if speaker_mask is not None:
        m = np.asarray(speaker_mask, dtype=bool)
        if m.shape != (t,):
            raise ValueError(f"speaker_mask must be (T,) = ({t},) bool, got shape {m.shape}")
        data = data[m[first : first + n]]
    return pd.DataFrame(data, columns=cols)


def turn_transactions(
    labels_a: np.ndarray,
    labels_b: np.ndarray,
    names: Sequence[str],
    talking: str = "talking",
    offset: int = 10,
    bag: int = 0,
) -> pd.DataFrame:
    """Transactions of a two-person conversation whose people take turns: each person is the
    speaker on the frames where their ``talking`` label is 1 and the other is the listener there.

    Parameters
    ----------
    labels_a, labels_b : ndarray of shape (T, K)
        Labels of the two people (bool or 1/0/UNKNOWN).
    names : sequence of str, length K
        The signal names, which must include ``talking``.
    talking : str, default="talking"
        The signal that tells the speaker.
    offset : int, default=10
        s, frames (>= 0).
    bag : int, default=0
        b, frames (>= 0).

    Returns
    -------
    pandas.DataFrame
        The rows of both roles, pooled (:func:`build_transactions` with ``speaker_mask``).

    Raises
    ------
    ValueError
        ``talking`` is not among ``names``, or as :func:`build_transactions`.
    """
    names = list(names)
    if talking not in names:
        raise ValueError(f"turn_transactions needs a {talking!r} signal to tell the speaker; names are {names}")
    k = names.index(talking)
    a, b = np.asarray(labels_a), np.asarray(labels_b)
    return pd.concat(
        [build_transactions(sp, li, names, offset, bag, speaker_mask=sp[:, k] == 1) for sp, li in ((a, b), (b, a))],
        ignore_index=True,
    )


def _association_rules(freq: pd.DataFrame, n_transactions: int, min_confidence: float) -> pd.DataFrame:
    """Mlxtend's association_rules across its API versions: >= 0.23.2 takes ``num_itemsets`` (the
    number of transactions) and from 0.23.4 ``return_metrics``; older versions take neither.
    """
    params = inspect.signature(association_rules).parameters
    kw: dict[str, Any] = {"metric": "confidence", "min_threshold": min_confidence}
    if "num_itemsets" in params:
        kw["num_itemsets"] = n_transactions
    if "return_metrics" in params:
        kw["return_metrics"] = ["antecedent support", "consequent support", "support", "confidence", "lift"]
    return association_rules(freq, **kw)


def rules_from_frame(rules: pd.DataFrame) -> list[Rule]:
    """Keep speaker -> listener rules of an mlxtend rules table; sorted by confidence, support.

    Parameters
    ----------
    rules : pandas.DataFrame
        mlxtend's ``association_rules`` table (antecedents, consequents, supports, confidence, lift).

    Returns
    -------
    list of Rule
        The rules whose antecedent is all speaker items and consequent all listener items, by
        confidence then support, largest first.
    """
    out = []
    for a, c, sup, conf, lift, asup, csup in zip(
        rules["antecedents"],
        rules["consequents"],
        rules["support"],
        rules["confidence"],
        rules["lift"],
        rules["antecedent support"],
        rules["consequent support"],
    ):
        if all(x.startswith(SPEAKER_PREFIX) for x in a) and all(y.startswith(LISTENER_PREFIX) for y in c):
            out.append(
                Rule(tuple(sorted(a)), tuple(sorted(c)), float(sup), float(conf), float(lift), float(asup), float(csup))
            )
    out.sort(key=lambda r: (-r.confidence, -r.support, r.antecedent, r.consequent))
    return out


def mine_transactions(
    transactions: pd.DataFrame,
    min_support: float = 0.01,
    min_confidence: float = 0.1,
    max_len: int | None = 4,
    algorithm: str = "apriori",
    low_memory: bool = True,
) -> list[Rule]:
    """Apriori (or FP-growth) + association rules over one-hot bool transactions (rows x items).

    Columns with no True value are dropped first (they cannot be frequent). ``low_memory=True`` is
    the default because it is also the faster apriori on long, sparse transaction tables (measured
    0.16 s against 2.9 s on 45,000 x 54 items at min_support 0.005, mlxtend 0.25). Returns the
    speaker -> listener rules with ``support >= min_support`` and ``confidence >= min_confidence``.

    Parameters
    ----------
    transactions : pandas.DataFrame
        One-hot bool transactions, rows x items ("S:<name>", "L:<name>").
    min_support : float, default=0.01
        Least support of a rule, in (0, 1].
    min_confidence : float, default=0.1
        Least confidence of a rule, in [0, 1].
    max_len : int or None, default=4
        Most items in an itemset; None for no limit.
    algorithm : {"apriori", "fpgrowth"}, default="apriori"
        The frequent-itemset algorithm.
    low_memory : bool, default=True
        mlxtend apriori's ``low_memory`` (unused by FP-growth).

    Returns
    -------
    list of Rule
        The rules, as :func:`rules_from_frame` sorts them; empty when nothing is frequent.

    Raises
    ------
    ValueError
        ``min_support`` or ``min_confidence`` out of range, or an unknown algorithm.
    """
    if not 0 < min_support <= 1 or not 0 <= min_confidence <= 1:
        raise ValueError(
            f"min_support must be in (0,1] and min_confidence in [0,1], got {min_support}, {min_confidence}"
        )
    if algorithm not in ("apriori", "fpgrowth"):
        raise ValueError(f"algorithm must be 'apriori' or 'fpgrowth', got {algorithm!r}")
    n = len(transactions)
    if n == 0:
        return []
    df = transactions.loc[:, transactions.to_numpy().any(axis=0)]
    if df.shape[1] == 0:
        return []
    if algorithm == "apriori":
        freq = apriori(df, min_support=min_support, use_colnames=True, max_len=max_len, low_memory=low_memory)
    else:
        freq = fpgrowth(df, min_support=min_support, use_colnames=True, max_len=max_len)
    if freq.empty or not (freq["itemsets"].map(len) > 1).any():
        return []
    return rules_from_frame(_association_rules(freq, n, min_confidence))


def mine_rules(
    speaker_labels: np.ndarray,
    listener_labels: np.ndarray,
    names: Sequence[str],
    offset: int = 10,
    min_support: float = 0.01,
    min_confidence: float = 0.1,
    bag: int = 0,
    max_len: int | None = 4,
    algorithm: str = "apriori",
) -> list[Rule]:
    """Rules speaker signals -> listener response ``offset`` frames later, for one recording.

    See :func:`build_transactions` and :func:`mine_transactions`.

    Parameters
    ----------
    speaker_labels, listener_labels : ndarray of shape (T, K)
        Labels of the speaker and the listener, bool (or 1/0/UNKNOWN).
    names : sequence of str, length K
        The signal names.
    offset : int, default=10
        s, frames (>= 0).
    min_support : float, default=0.01
        Least support of a rule, in (0, 1].
    min_confidence : float, default=0.1
        Least confidence of a rule, in [0, 1].
    bag : int, default=0
        b, frames (>= 0).
    max_len : int or None, default=4
        Most items in an itemset; None for no limit.
    algorithm : {"apriori", "fpgrowth"}, default="apriori"
        The frequent-itemset algorithm.

    Returns
    -------
    list of Rule
        The speaker -> listener rules.

    Raises
    ------
    ValueError
        Bad labels or parameters (see :func:`build_transactions` and :func:`mine_transactions`).
    """
    return mine_rules_sessions(
        [(speaker_labels, listener_labels)], names, offset, min_support, min_confidence, bag, max_len, algorithm
    )


def mine_rules_sessions(
    sessions: Sequence[tuple[np.ndarray, np.ndarray]],
    names: Sequence[str],
    offset: int = 10,
    min_support: float = 0.01,
    min_confidence: float = 0.1,
    bag: int = 0,
    max_len: int | None = 4,
    algorithm: str = "apriori",
) -> list[Rule]:
    """Like :func:`mine_rules` over several recordings of one scenario: each
    ``(speaker_labels, listener_labels)`` pair is bagged on its own, then the transactions are pooled.

    Parameters
    ----------
    sessions : sequence of (ndarray of shape (T, K), ndarray of shape (T, K))
        (speaker_labels, listener_labels) per recording; T may differ between recordings.
    names : sequence of str, length K
        The signal names.
    offset, min_support, min_confidence, bag, max_len, algorithm
        As :func:`mine_rules`.

    Returns
    -------
    list of Rule
        The speaker -> listener rules of the pooled transactions.

    Raises
    ------
    ValueError
        No sessions, or bad labels or parameters.
    """
    if not sessions:
        raise ValueError("sessions is empty: give at least one (speaker_labels, listener_labels) pair")
    tx = pd.concat([build_transactions(s, li, names, offset, bag) for s, li in sessions], ignore_index=True)
    return mine_transactions(tx, min_support, min_confidence, max_len, algorithm)


@dataclass(frozen=True)
class RuleComparison:
    """The same rule mined in two scenarios (Okwechime Table 2, a = interested listener, b = not
    interested).

    Parameters
    ----------
    antecedent : tuple of str
        Speaker items, sorted.
    consequent : tuple of str
        Listener items, sorted.
    confidence_a, confidence_b : float
        The rule's confidence in scenario a and b.
    support_a, support_b : float
        The rule's support in scenario a and b.
    ratio : float
        confidence_a / confidence_b.
    """

    antecedent: tuple[str, ...]
    consequent: tuple[str, ...]
    confidence_a: float
    confidence_b: float
    support_a: float
    support_b: float
    ratio: float

    def to_dict(self) -> dict[str, Any]:
        """The comparison as a JSON-able dict (item tuples as lists).

        Returns
        -------
        dict of str to object
            Every field by name.
        """
        return _as_json(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> RuleComparison:
        """The inverse of :meth:`to_dict`.

        Parameters
        ----------
        d : mapping of str to object
            Every field by name.

        Returns
        -------
        RuleComparison
            The comparison.
        """
        return cls(
            tuple(d["antecedent"]),
            tuple(d["consequent"]),
            float(d["confidence_a"]),
            float(d["confidence_b"]),
            float(d["support_a"]),
            float(d["support_b"]),
            float(d["ratio"]),
        )


def compare_scenarios(rules_a: Sequence[Rule], rules_b: Sequence[Rule]) -> list[RuleComparison]:
    """Pair rules with the same antecedent and consequent in both scenarios (rules found in only
    one are left out) and give the ratio of confidences; sorted by ratio, largest first.

    Parameters
    ----------
    rules_a : sequence of Rule
        The rules of scenario a (interested listener).
    rules_b : sequence of Rule
        The rules of scenario b (not interested).

    Returns
    -------
    list of RuleComparison
        The paired rules.
    """
    by_key = {r.key: r for r in rules_b}
    out = [
        RuleComparison(
            r.antecedent,
            r.consequent,
            r.confidence,
            by_key[r.key].confidence,
            r.support,
            by_key[r.key].support,
            r.confidence / by_key[r.key].confidence,
        )
        for r in rules_a
        if r.key in by_key
    ]
    out.sort(key=lambda c: (-c.ratio, c.antecedent, c.consequent))
    return out


# ---------------------------------------------------------------- rules file (read by the responder)


@dataclass(frozen=True)
class RulesFile:
    """Contents of a rules file.

    Parameters
    ----------
    version : int
        Format version.
    params : dict of str to object
        The mining parameters.
    scenarios : dict of str to list of Rule
        Rules per scenario (e.g. "interested", "not_interested").
    comparisons : list of RuleComparison
        The paired comparisons.
    """

    version: int
    params: dict[str, Any]
    scenarios: dict[str, list[Rule]]
    comparisons: list[RuleComparison] = field(default_factory=list)


def write_rules(
    path: str | os.PathLike[str],
    scenarios: Mapping[str, Sequence[Rule]],
    params: Mapping[str, Any],
    comparisons: Sequence[RuleComparison] = (),
) -> None:
    """Write a versioned JSON rules file.

    The format::

        {"format": "counterpart.labeller.rules", "version": 1,
         "params": {"offset": 10, "bag": 0, "min_support": ..., "fps": ..., "inputs": {...}, ...},
         "scenarios": {"interested": [rule, ...], "not_interested": [...]},
         "comparisons": [{"antecedent": [...], "consequent": [...], "confidence_a": ...,
                          "confidence_b": ..., "support_a": ..., "support_b": ..., "ratio": ...}]}

    where a rule is {"antecedent": ["S:nod"], "consequent": ["L:nod"], "support", "confidence",
    "lift", "antecedent_support", "consequent_support"}. The file is written whole or not at all
    (through a ``.tmp`` file).

    Parameters
    ----------
    path : str or PathLike
        The file to write.
    scenarios : mapping of str to sequence of Rule
        Rules per scenario.
    params : mapping of str to object
        The mining parameters.
    comparisons : sequence of RuleComparison, default=()
        The paired comparisons.
    """
    doc = {
        "format": RULES_FORMAT,
        "version": RULES_VERSION,
        "params": dict(params),
        "scenarios": {k: [r.to_dict() for r in v] for k, v in scenarios.items()},
        "comparisons": [c.to_dict() for c in comparisons],
    }
    tmp = f"{os.fspath(path)}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    os.replace(tmp, path)


def read_rules(path: str | os.PathLike[str]) -> RulesFile:
    """Read a file written by :func:`write_rules`.

    Parameters
    ----------
    path : str or PathLike
        The rules file.

    Returns
    -------
    RulesFile
        Its contents.

    Raises
    ------
    ValueError
        The file is not a rules file, or its version is not supported (too new).
    """
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    if not isinstance(doc, dict) or doc.get("format") != RULES_FORMAT:
        raise ValueError(f'{path}: not a rules file (expected "format": "{RULES_FORMAT}")')
    version = int(doc.get("version", 0))
    if version < 1 or version > RULES_VERSION:
        raise ValueError(
            f"{path}: rules file version {version} is not supported "
            f"(this reader knows 1..{RULES_VERSION}); upgrade counterpart"
        )
    return RulesFile(
        version=version,
        params=dict(doc.get("params", {})),
        scenarios={k: [Rule.from_dict(r) for r in v] for k, v in doc.get("scenarios", {}).items()},
        comparisons=[RuleComparison.from_dict(c) for c in doc.get("comparisons", [])],
    )


# ---------------------------------------------------------------- label streams


@dataclass(frozen=True)
class LabelStreams:
    """Per-frame labels of the people of one recording.

    Parameters
    ----------
    names : tuple of str, length K
        The signal names.
    people : dict of str to ndarray of shape (T, K), dtype int8
        Person id -> labels (1/0/UNKNOWN).
    fps : float or None, default=None
        Frame rate, Hz, or None when the file does not say.
    """

    names: tuple[str, ...]
    people: dict[str, np.ndarray]
    fps: float | None = None


def _check_labels(a: np.ndarray, what: str) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype == bool:
        return a.astype(np.int8)
    if not np.issubdtype(a.dtype, np.number):
        raise ValueError(f"{what}: labels must be numeric 1/0/{UNKNOWN} or bool, got dtype {a.dtype}")
    if np.issubdtype(a.dtype, np.floating):
        a = np.where(np.isnan(a), UNKNOWN, a)  # float32 label files may mark UNKNOWN as nan
    bad = ~np.isin(a, (1, 0, UNKNOWN))
    if bad.any():
        raise ValueError(f"{what}: labels must be 1, 0 or {UNKNOWN}; found {np.unique(a[bad])[:5]}")
    return a.astype(np.int8)


def read_labels_npz(path: str | os.PathLike[str]) -> LabelStreams:
    """Label streams from an NPZ with keys ``signals_a`` (T,K), ``signals_b`` (T,K) (bool, or
    1/0/-1 integers, or float 1/0/-1 with nan for UNKNOWN), ``signal_names`` (K,) str and ``fps``
    (scalar) -- the keys of the project's two-person trajectory file (``counterpart.body.trajectory``); other
    keys are ignored.

    Parameters
    ----------
    path : str or PathLike
        The NPZ file.

    Returns
    -------
    LabelStreams
        People ``a`` and ``b``.

    Raises
    ------
    ValueError
        Missing keys, labels other than 1/0/UNKNOWN, or streams of wrong or different shapes.
    """
    with np.load(path, allow_pickle=False) as z:
        missing = [k for k in ("signals_a", "signals_b", "signal_names") if k not in z.files]
        if missing:
            raise ValueError(
                f"{path}: missing keys {missing}; a label NPZ needs signals_a, "
                f"signals_b, signal_names and fps (has {z.files})"
            )
        names = tuple(str(x) for x in z["signal_names"])
        people = {p: _check_labels(z[f"signals_{p}"], f"{path}:signals_{p}") for p in ("a", "b")}
        fps = float(z["fps"]) if "fps" in z.files else None
    for p, a in people.items():
        if a.ndim != 2 or a.shape[1] != len(names):
            raise ValueError(f"{path}: signals_{p} has shape {a.shape}, expected (T, {len(names)})")
    if people["a"].shape != people["b"].shape:
        raise ValueError(
            f"{path}: signals_a {people['a'].shape} and signals_b "
            f"{people['b'].shape} must have the same shape (one clock)"
        )
    return LabelStreams(names, people, fps)


def read_labels_csv(path: str | os.PathLike[str]) -> LabelStreams:
    """Label streams from CSV.

    Format: an optional first line ``# fps=25``; a header row with a ``person`` column, an optional
    ``frame`` column and one column per signal name; one row per person and frame with values 1, 0
    or -1 (UNKNOWN; an empty cell is UNKNOWN too). Rows are ordered by ``frame`` when present, else
    kept in file order. Every person must have the same frames.

    Parameters
    ----------
    path : str or PathLike
        The CSV file.

    Returns
    -------
    LabelStreams
        The people by their ``person`` value.

    Raises
    ------
    ValueError
        No ``person`` column, no signal columns, labels other than 1/0/UNKNOWN, or people with
        different numbers of frames.
    """
    fps = None
    with open(path, encoding="utf-8", newline="") as f:
        first = f.readline()
        if first.startswith("#"):
            text = first.lstrip("#").strip()
            if text.startswith("fps"):
                fps = float(text.split("=", 1)[1] if "=" in text else text.split(":", 1)[1])
        else:
            f.seek(0)
        df = pd.read_csv(f, dtype={"person": str})
    if "person" not in df.columns:
        raise ValueError(f"{path}: no 'person' column; header must be person[,frame],<signals...>")
    names = tuple(c for c in df.columns if c not in ("person", "frame"))
    if not names:
        raise ValueError(f"{path}: no signal columns besides person/frame")
    people: dict[str, np.ndarray] = {}
    for pid, g in df.groupby("person", sort=False):
        if "frame" in g.columns:
            g = g.sort_values("frame", kind="stable")
        vals = g.loc[:, list(names)].fillna(UNKNOWN).to_numpy()
        people[str(pid)] = _check_labels(vals, f"{path}: person {pid}")
    lens = {p: a.shape[0] for p, a in people.items()}
    if len(set(lens.values())) > 1:
        raise ValueError(f"{path}: people have different numbers of frames {lens}")
    return LabelStreams(names, people, fps)


def write_labels_csv(path: str | os.PathLike[str], streams: LabelStreams) -> None:
    """Write :class:`LabelStreams` in the format :func:`read_labels_csv` reads.

    Parameters
    ----------
    path : str or PathLike
        The CSV file to write.
    streams : LabelStreams
        The labels; frames are numbered from 0.
    """
    with open(path, "w", encoding="utf-8", newline="") as f:
        if streams.fps is not None:
            f.write(f"# fps={streams.fps:g}\n")
        w = csv.writer(f)
        w.writerow(["person", "frame", *streams.names])
        for pid, a in streams.people.items():
            for t, row in enumerate(np.asarray(a, dtype=np.int64).tolist()):
                w.writerow([pid, t, *row])


def read_labels(path: str | os.PathLike[str]) -> LabelStreams:
    """Dispatch on the extension: ``.npz`` -> :func:`read_labels_npz`, ``.csv`` -> :func:`read_labels_csv`.

    Parameters
    ----------
    path : str or PathLike
        The label file.

    Returns
    -------
    LabelStreams
        Its labels.

    Raises
    ------
    ValueError
        An extension other than ``.npz`` or ``.csv``, or a bad file.
    """
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext == ".npz":
        return read_labels_npz(path)
    if ext == ".csv":
        return read_labels_csv(path)
    raise ValueError(f"{path}: unknown label file type {ext!r}; use .npz or .csv")
