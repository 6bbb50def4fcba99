"""From where goals are scored: for every goal in some recordings, the
ball's distance to the goal's centre at the scoring team's last kick
before it, and the time from that kick to the goal.

    naosoccer match --blue ppo:assets/policies/ppo-team-seed3 --red scripted \
        --seed 1 --minutes 10 --record m1.mcap          # ... and more seeds
    python goal-distance.py 'm*.mcap'

Needs the `mcap` and `protobuf` packages (docs/RECORDINGS.md, "Reading a
recording from Python"). Own goals and goals with no kick of the scoring
team before them are left out. Blue is players 0-3, red 4-7; the goal a
goal went into is the one on the ball's side of the pitch when it was
scored.
"""

import glob
import json
import math
import sys

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader

HALF_LENGTH = 4.5  # the goal lines' x, metres
CONTROL_HZ = 10


def message_class(schema):
    pool = descriptor_pool.DescriptorPool()
    for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def goals(path):
    """(team, distance in m, seconds from the kick to the goal) per goal."""
    events, ball, tf_class = [], [], None
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(
            topics=["/match/events", "/foxglove/tf"]
        ):
            if channel.topic == "/match/events":
                events.append(json.loads(message.data))
            else:
                tf_class = tf_class or message_class(schema)
                b = tf_class.FromString(message.data).transforms[8].translation
                ball.append((b.x, b.y))  # one a tick, from tick 0
    for i, e in enumerate(events):
        if e["kind"] != "goal" or e.get("phase") == "own_goal":
            continue
        blue = e["team"] == "blue"
        kicks = [k for k in events[:i] if k["kind"] == "kick" and (k["robot"] < 4) == blue]
        if not kicks:
            continue
        kick = kicks[-1]
        goal_x = HALF_LENGTH if ball[min(e["tick"], len(ball) - 1)][0] > 0 else -HALF_LENGTH
        x, y = ball[kick["tick"]]
        yield e["team"], math.hypot(goal_x - x, y), (e["tick"] - kick["tick"]) / CONTROL_HZ


def main():
    rows = [g for pattern in sys.argv[1:] for path in sorted(glob.glob(pattern)) for g in goals(path)]
    for team in ("blue", "red"):
        d = sorted(r[1] for r in rows if r[0] == team)
        t = sorted(r[2] for r in rows if r[0] == team)
        if not d:
            continue
        print(
            f"{team}: {len(d)} goals; distance at the last own kick: median {d[len(d) // 2]:.1f} m, "
            f"under 2 m {sum(x < 2 for x in d)}, 2 to 4 m {sum(2 <= x < 4 for x in d)}, "
            f"4 m or more {sum(x >= 4 for x in d)}; kick to goal: median {t[len(t) // 2]:.1f} s"
        )


if __name__ == "__main__":
    main()
