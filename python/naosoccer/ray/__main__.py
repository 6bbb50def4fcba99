"""``python -m naosoccer.ray eval|league``: ``naosoccer eval`` and round-robin
leagues with every match a Ray task (docs/RAY.md)."""

from __future__ import annotations

import argparse
import os
import sys
from typing import List, Optional

from ..evaluation import EvalSpec, dumps, format_table
from ..league import markdown


def _u64(text: str) -> int:
    v = int(text)
    if not 0 <= v < 1 << 64:
        raise argparse.ArgumentTypeError(f"{text} is not in 0..2^64-1")
    return v


def _positive(text: str) -> float:
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return v


def _cluster_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("cluster")
    g.add_argument(
        "--address",
        default=None,
        help="Ray cluster to connect to (default: $RAY_ADDRESS; with neither, a local Ray is started)",
    )
    g.add_argument(
        "--num-cpus",
        type=int,
        default=None,
        help="worker processes of the local Ray started when there is no address (default: all cores)",
    )
    g.add_argument(
        "--binary",
        default=None,
        help="the naosoccer binary on the nodes (default: $NAOSOCCER_BIN, then the repository's target/release)",
    )


def _match_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--seed", type=_u64, default=0, help="as naosoccer eval's [default: 0]")
    p.add_argument("--config", default=None, help="match configuration (TOML); default: the built-in assets/match.toml")
    p.add_argument("--minutes", type=_positive, default=None, help="match length in minutes, overriding the configuration")


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m naosoccer.ray",
        description="naosoccer evaluations and leagues with every match a Ray task (docs/RAY.md)",
    )
    sub = p.add_subparsers(dest="command", required=True)

    e = sub.add_parser(
        "eval",
        help="naosoccer eval on a Ray cluster: same options, same table, same --json",
        description="Plays the matches of `naosoccer eval` as Ray tasks (one match a task, each running "
        "the naosoccer binary on its node) and prints the same table, or with --json the same JSON object: "
        "same per-match scores, same statistics and intervals; only wall_seconds differs.",
    )
    e.add_argument("--blue", required=True, help="first team: any team spec naosoccer eval takes")
    e.add_argument("--red", default="scripted", help="second team [default: scripted]")
    e.add_argument("--matches", type=int, default=50, help="matches to play [default: 50]")
    _match_options(e)
    e.add_argument("--both-sides", action="store_true", help="play every other match with the sides swapped")
    e.add_argument(
        "--legacy-seeds", action="store_true", help="seed the matches as naosoccer eval --legacy-seeds does"
    )
    e.add_argument("--json", action="store_true", help="one JSON object instead of the table")
    _cluster_options(e)

    lg = sub.add_parser(
        "league",
        help="a round robin of N teams; standings with W/D/L, goals and a Bradley–Terry rating",
        description="Every pairing of the teams (in the order given, the first named playing --blue) plays "
        "`naosoccer eval --matches M --seed S --both-sides`; all matches run as Ray tasks. Prints the "
        "standings as markdown (or JSON with --json) and writes league.md and league.json into --out.",
    )
    lg.add_argument("teams", nargs="+", help="team specs, as naosoccer eval's --blue")
    lg.add_argument("--matches", type=int, default=10, help="matches a pairing [default: 10]")
    _match_options(lg)
    lg.add_argument("--out", default=None, help="directory to write league.md and league.json into")
    lg.add_argument("--json", action="store_true", help="print the JSON instead of the markdown")
    _cluster_options(lg)
    return p


def main(argv: Optional[List[str]] = None) -> int:
    args = parser().parse_args(argv)
    if args.matches < 1:
        print("error: --matches must be at least 1", file=sys.stderr)
        return 2
    import ray

    try:
        return _run(args)
    except ray.exceptions.RayTaskError as e:
        # A match failed on its node (a bad team spec, no binary there, ...):
        # its own error, not Ray's traceback around it.
        print(f"error: {getattr(e, 'cause', None) or e}", file=sys.stderr)
        return 1


def _run(args: argparse.Namespace) -> int:
    from . import connect, run_eval, run_league

    connect(args.address, args.num_cpus, args.binary, log_to_driver=False)
    if args.command == "eval":
        spec = EvalSpec(
            blue=args.blue, red=args.red, matches=args.matches, seed=args.seed,
            both_sides=args.both_sides, legacy_seeds=args.legacy_seeds,
            config=args.config, minutes=args.minutes,
        )
        doc = run_eval(spec, binary=args.binary)
        sys.stdout.write(dumps(doc) + "\n" if args.json else format_table(doc))
        return 0
    if len(args.teams) < 2 or len(set(args.teams)) != len(args.teams):
        print("error: a league needs two or more distinct teams", file=sys.stderr)
        return 2
    doc = run_league(
        args.teams, matches=args.matches, seed=args.seed, config=args.config,
        minutes=args.minutes, binary=args.binary,
    )
    md = markdown(doc)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "league.md"), "w", encoding="utf-8") as f:
            f.write(md)
        with open(os.path.join(args.out, "league.json"), "w", encoding="utf-8") as f:
            f.write(dumps(doc) + "\n")
    sys.stdout.write(dumps(doc) + "\n" if args.json else md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
