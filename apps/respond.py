"""``counterpart respond --model FILE --input a.npz --out b.npz``: offline partner generation.

The input is a two-person trajectory file; person ``--observed`` (a or b) is fed to the model
frame by frame (with its signals for the listener model) and the output file holds the same
observed person and the generated partner in the other slot (label ``generated:<label>``).
``--model`` is a model file or ``default:NAME`` (dual-hmm, joint-shape... built when missing);
``--emotion``/``--strength`` restyle the partner with the default emotion model (the gpdm model
takes them as its style variables instead).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.messages import EMOTIONS, INTEREST_LEVELS

#: the one-line help of this command in `counterpart --help`
HELP = "offline: generate the partner for one person's trajectory"


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the options of ``counterpart respond``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("--model", required=True, help="model file, or default:dual-hmm / default:listener")
    p.add_argument("--input", required=True, help="two-person trajectory file (.npz)")
    p.add_argument("--out", required=True, help="trajectory file to write (.npz)")
    p.add_argument("--observed", choices=("a", "b"), default="a", help="the person fed to the model")
    p.add_argument("--interest", type=int, choices=INTEREST_LEVELS, default=3, help="listener interest level")
    p.add_argument("--emotion", choices=EMOTIONS, default="neutral", help="the partner's emotion")
    p.add_argument("--strength", type=float, default=0.0, help="emotion strength in [0, 1]")


def generate(model: object, traj: TwoPersonTrajectory, observed: str = "a", interest: int = 3) -> np.ndarray:
    """The partner's joints for one person of ``traj`` (3D models: dual-hmm, gpdm, listener), the model
    stepped on its own frames (``AtModelRate``) whatever the trajectory's frame rate.

    Parameters
    ----------
    model : object
        A loaded model whose ``name`` is ``dual-hmm``, ``gpdm`` or ``listener``.
    traj : TwoPersonTrajectory
        The two-person trajectory; the listener model also needs its signals.
    observed : {"a", "b"}, default="a"
        The person fed to the model.
    interest : int, default=3
        The listener's interest level (listener model only).

    Returns
    -------
    ndarray of shape (T, 14, 3)
        The generated partner's joints, metres, world frame.

    Raises
    ------
    ValueError
        If the model does not generate 3D joints, or the listener model gets a file without signals.
    """
    from counterpart.nodes.responder.model_clock import AtModelRate

    obs = traj.a if observed == "a" else traj.b
    name = getattr(model, "name", "")
    if name not in ("dual-hmm", "gpdm", "listener"):
        raise ValueError(f"model {name!r} does not generate 3D joints; use dual-hmm, gpdm or listener")
    steps = [model.step] * len(obs)
    if name == "listener":
        if traj.signals_a is None:
            raise ValueError("the listener model needs the observed person's signals in the input file")
        sig = traj.signals_a if observed == "a" else traj.signals_b
        model.interest = interest
        heard = [{n: bool(v == 1) for n, v in zip(traj.signal_names, row)} for row in sig]
        steps = [lambda x, h=h: model.step(h, x) for h in heard]
    # as the responder node: the model steps on its own frames whatever the file's frame rate
    rate = AtModelRate.for_model(model, traj.fps)
    model.reset()
    out = np.stack([rate(step, x, t / traj.fps) for t, (step, x) in enumerate(zip(steps, obs))])
    model.reset()
    return out


def main(args: argparse.Namespace) -> int:
    """Run ``counterpart respond``: write the input's observed person and the generated partner.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of :func:`add_arguments`.

    Returns
    -------
    int
        Exit code: 0, or 2 for a bad model, input or option (the message goes to stderr).
    """
    from counterpart.nodes.responder.models import load_default, load_model

    try:
        if args.model.startswith("default:"):
            model = load_default(args.model.split(":", 1)[1], lambda s: print(s, file=sys.stderr))
        else:
            model = load_model(args.model)
        traj = TwoPersonTrajectory.load(args.input)
        gpdm = getattr(model, "name", "") == "gpdm"
        if gpdm:  # the gpdm's style is its own input, not a filter afterwards
            model.set_style(args.emotion, args.strength)
        partner = generate(model, traj, args.observed, args.interest)
        if args.emotion != "neutral" and args.strength > 0 and not gpdm:
            partner = load_default("emotion").modulate(partner, args.emotion, args.strength)
        obs = traj.a if args.observed == "a" else traj.b
        a, b = (obs, partner) if args.observed == "a" else (partner, obs)
        out = TwoPersonTrajectory(
            a=a,
            b=b,
            fps=traj.fps,
            label=f"generated:{traj.label}",
            meta={
                "model": getattr(model, "name", ""),
                "input": args.input,
                "observed": args.observed,
                "emotion": args.emotion,
                "strength": args.strength,
            },
        )
        out.save(args.out)
    except (ValueError, FileNotFoundError) as e:
        print(f"counterpart respond: {e}", file=sys.stderr)
        return 2
    print(f"wrote {args.out} ({out.n_frames} frames)", file=sys.stderr)
    return 0
