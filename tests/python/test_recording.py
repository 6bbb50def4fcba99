"""A full 10-minute recording read by the Python `mcap` reader.

Checks what a user outside Rust relies on: message counts per channel equal
what the writer reported, every naosoccer message parses, the Foxglove
channels validate against the published Foxglove JSON schemas (the
`@foxglove/schemas` npm package, installed by scripts/setup), and the file
stays small.
"""

import json
import os
import subprocess
from collections import Counter
from pathlib import Path

import jsonschema
import pytest
from mcap.reader import make_reader

REPO = Path(__file__).resolve().parents[2]


def naosoccer_bin() -> Path:
    env = os.environ.get("NAOSOCCER_BIN")
    if env:
        return Path(env)
    for profile in ("debug", "release"):
        p = REPO / "target" / profile / "naosoccer"
        if p.exists():
            return p
    pytest.fail("no naosoccer binary: build it first (scripts/test does) or set NAOSOCCER_BIN")


def published_schema(name: str) -> dict:
    pkg = REPO / ".foxglove-schemas"
    if not (pkg / "package.json").exists():
        pytest.fail("the published Foxglove schemas are missing: run scripts/setup")
    out = subprocess.run(
        ["node", "-e", f"process.stdout.write(JSON.stringify(require({json.dumps(str(pkg))} + '/dist/jsonschema/index.js').{name}))"],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)


@pytest.fixture(scope="module")
def full_match(tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "full.mcap"
    out = subprocess.run(
        [str(naosoccer_bin()), "match", "--seed", "1", "--record", str(path), "--json"],
        check=True,
        capture_output=True,
        text=True,
    )
    report = json.loads(out.stdout)
    return path, report


def test_counts_match_the_writer_and_messages_parse(full_match):
    path, report = full_match
    written = report["recording"]["messages"]
    counts = Counter()
    final = None
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            counts[channel.topic] += 1
            assert channel.message_encoding == "json"
            assert schema.encoding == "jsonschema"
            data = json.loads(message.data)
            if channel.topic == "/match/stats":
                final = data
            elif channel.topic == "/match/actions":
                assert len(data["actions"]) == 8
    assert dict(counts) == {k: v for k, v in written.items() if v > 0}
    assert counts["/match/actions"] == report["ticks"] == 6000
    assert counts["/match/state"] == report["ticks"] + 1
    assert final is not None and final["completed"]
    assert final["score"] == report["score"]


def test_foxglove_channels_validate_against_published_schemas(full_match):
    path, _ = full_match
    scene = published_schema("SceneUpdate")
    tf = published_schema("FrameTransforms")
    scene_v = jsonschema.Draft202012Validator(scene)
    tf_v = jsonschema.Draft202012Validator(tf)
    seen = Counter()
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(topics=["/foxglove/scene", "/foxglove/tf"]):
            data = json.loads(message.data)
            if channel.topic == "/foxglove/scene":
                assert schema.name == "foxglove.SceneUpdate"
                scene_v.validate(data)
            else:
                assert schema.name == "foxglove.FrameTransforms"
                tf_v.validate(data)
                assert len(data["transforms"]) == 9
            seen[channel.topic] += 1
    assert seen["/foxglove/scene"] >= 1
    assert seen["/foxglove/tf"] == 6001


def test_full_match_file_is_small(full_match):
    path, _ = full_match
    size = path.stat().st_size
    print(f"10-minute recording: {size / 1e6:.2f} MB")
    assert size < 20_000_000
