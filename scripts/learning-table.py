#!/usr/bin/env python3
"""Markdown tables of `naosoccer eval --json` results, as docs/LEARNING.md shows them.

    naosoccer eval --blue ppo:assets/policies/ppo-seed1 --matches 50 --seed 7 --json > ppo-1.json
    ...
    python3 scripts/learning-table.py ppo-1.json ppo-2.json dqn-1.json ...

One row per file (the --blue team's figures, mean ± 95% CI over its
matches, whichever colour it played with --both-sides), then one row per
group pooling the matches of all its files: a group is the blue team's name
without its trailing seed (`ppo:assets/policies/ppo-seed1` and
`ppo:assets/policies/ppo-seed2` pool as `ppo:assets/policies/ppo`) against
one opponent (the --red team). Win
rates carry their Wilson score 95% interval. Standard library only.
"""

import json
import math
import re
import sys

# Two-sided 95% Student-t quantiles; above 120 degrees of freedom, the normal's.
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306,
       9: 2.262, 10: 2.228, 15: 2.131, 20: 2.086, 30: 2.042, 40: 2.021, 60: 2.000,
       120: 1.980}


def t95(df):
    if df <= 0:
        return float("nan")
    keys = sorted(k for k in T95 if k >= df)
    return T95[keys[0]] if keys else 1.960


def mean_ci(xs):
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan")
    var = sum((x - m) ** 2 for x in xs) / (n - 1)
    return m, t95(n - 1) * math.sqrt(var / n)


def wilson(k, n, z=1.96):
    """Wilson score interval of k successes in n trials, as (rate, low, high)."""
    if n == 0:
        return float("nan"), float("nan"), float("nan")
    p = k / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return p, min(max(centre - half, 0.0), p), max(min(centre + half, 1.0), p)


def fmt_rate(k, n):
    p, lo, hi = wilson(k, n)
    return f"{100 * p:.1f}% [{100 * lo:.1f}, {100 * hi:.1f}]"


def sides(r):
    """'both' when half the matches swapped the sides, else 'blue'."""
    return "both" if r.get("both_sides") else "blue"


def per_match(result):
    """Per-match (blue goals, red goals); control, passes and shots are only
    summarised in the file."""
    return [(b, r) for b, r in result["scores"]]


def row(name, r):
    b = r["blue"]
    fmt = lambda f: f"{b[f]['mean']:.2f} ± {b[f]['ci95']:.2f}"
    return (f"| {name} | {r['red']['name']} | {fmt('goals')} | {b['control_rate_percent']['mean']:.1f}% ± "
            f"{b['control_rate_percent']['ci95']:.1f} | {fmt('passes')} | {fmt('shots')} | "
            f"{b['wins']} / {b['draws']} / {b['losses']} | {fmt_rate(b['wins'], r['matches'])} | "
            f"{sides(r)} | {r['red']['goals']['mean']:.2f} |")


def main(paths):
    if not paths:
        sys.exit(__doc__)
    results = []
    for p in paths:
        with open(p) as f:
            results.append((p, json.load(f)))
    print("| team | opponent | goals / match | ball control | passes / match | shots / match "
          "| W / D / L | win rate [Wilson 95%] | sides | goals conceded / match |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for _, r in results:
        print(row(r["blue"]["name"], r))
    groups = {}
    for _, r in results:
        team = re.sub(r"[-_]?seed\d+$", "", r["blue"]["name"])
        groups.setdefault((team, r["red"]["name"]), []).append(r)
    print()
    print("| team (runs pooled) | opponent | matches | goals / match | goals conceded / match "
          "| ball control (mean of runs) | W / D / L | win rate [Wilson 95%] |")
    print("|---|---|---|---|---|---|---|---|")
    for (algo, opponent), rs in groups.items():
        scores = [s for r in rs for s in per_match(r)]
        gf = mean_ci([float(b) for b, _ in scores])
        ga = mean_ci([float(r_) for _, r_ in scores])
        ctl = mean_ci([r["blue"]["control_rate_percent"]["mean"] for r in rs])
        w = sum(b > r_ for b, r_ in scores)
        d = sum(b == r_ for b, r_ in scores)
        l_ = sum(b < r_ for b, r_ in scores)
        runs = f"{len(rs)} run{'s' if len(rs) > 1 else ''}"
        print(f"| {algo} ({runs}) | {opponent} | {len(scores)} | {gf[0]:.2f} ± {gf[1]:.2f} | "
              f"{ga[0]:.2f} ± {ga[1]:.2f} | {ctl[0]:.1f}% ± {ctl[1]:.1f} | {w} / {d} / {l_} | "
              f"{fmt_rate(w, len(scores))} |")


if __name__ == "__main__":
    main(sys.argv[1:])
