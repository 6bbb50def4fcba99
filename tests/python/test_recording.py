"""A full 10-minute recording read by the Python `mcap` reader.

Checks what a user outside Rust relies on: message counts per channel equal
what the writer reported, every naosoccer message parses as JSON, the
Foxglove channels (protobuf, the Foxglove SDK's types) decode with nothing
but the descriptors the file carries, and what they hold validates against
the published Foxglove schemas (the `@foxglove/schemas` npm package,
installed by scripts/setup), and the file stays small.
"""

import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import jsonschema
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
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


def protobuf_class(schema):
    """The message class of a protobuf schema record, from the
    FileDescriptorSet it carries alone (dependencies come first in it)."""
    assert schema.encoding == "protobuf"
    files = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


TIME_TYPES = ("google.protobuf.Timestamp", "google.protobuf.Duration")


def foxglove_json(msg) -> dict:
    """A decoded Foxglove protobuf message in the Foxglove JSON form the
    published JSON schemas describe: every field present (defaults
    included), times as {sec, nsec}, enums as their numbers."""
    if msg.DESCRIPTOR.full_name in TIME_TYPES:
        return {"sec": msg.seconds, "nsec": msg.nanos}
    out = {}
    for field in msg.DESCRIPTOR.fields:
        value = getattr(msg, field.name)
        if field.message_type is not None:
            out[field.name] = [foxglove_json(v) for v in value] if field.is_repeated else foxglove_json(value)
        else:
            out[field.name] = list(value) if field.is_repeated else value
    return out


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
            if channel.topic.startswith("/foxglove/"):
                assert channel.message_encoding == "protobuf"
                assert schema.encoding == "protobuf"
                continue
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


def test_foxglove_channels_decode_and_validate_against_published_schemas(full_match):
    path, _ = full_match
    scene = published_schema("SceneUpdate")
    tf = published_schema("FrameTransforms")
    scene_v = jsonschema.Draft202012Validator(scene)
    tf_v = jsonschema.Draft202012Validator(tf)
    seen = Counter()
    classes = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(topics=["/foxglove/scene", "/foxglove/tf"]):
            if schema.id not in classes:
                classes[schema.id] = protobuf_class(schema)
            decoded = classes[schema.id].FromString(message.data)
            # Nothing left over: every byte is a field of the schema.
            assert decoded.SerializeToString() == message.data
            data = foxglove_json(decoded)
            if channel.topic == "/foxglove/scene":
                assert schema.name == "foxglove.SceneUpdate"
                scene_v.validate(data)
                ids = [e["id"] for e in data["entities"]]
                assert ids == ["pitch"] + [f"robot_{i}" for i in range(8)] + ["ball"]
            else:
                assert schema.name == "foxglove.FrameTransforms"
                tf_v.validate(data)
                assert len(data["transforms"]) == 9
                stamp = data["transforms"][0]["timestamp"]
                # Game time: tick t at t / 10 s.
                assert stamp["sec"] * 10**9 + stamp["nsec"] == message.log_time
            seen[channel.topic] += 1
    assert seen["/foxglove/scene"] >= 1
    assert seen["/foxglove/tf"] == 6001


def test_full_match_file_is_small(full_match):
    path, _ = full_match
    size = path.stat().st_size
    print(f"10-minute recording: {size / 1e6:.2f} MB")
    assert size < 20_000_000


def python_blocks(doc: Path) -> list[str]:
    """The ```python blocks of a Markdown file, in order."""
    blocks, current = [], None
    for line in doc.read_text().splitlines():
        if current is None and line.strip() == "```python":
            current = []
        elif current is not None and line.strip() == "```":
            blocks.append("\n".join(current))
            current = None
        elif current is not None:
            current.append(line)
    return blocks


def test_every_python_snippet_of_recordings_md_runs(full_match, tmp_path):
    """docs/RECORDINGS.md's readers, run as written in a directory holding
    the files they open: `seed7.mcap` (a whole match) and `killed.mcap` (the
    same file cut short at several places, as a killed server leaves it)."""
    path, _ = full_match
    data = path.read_bytes()
    (tmp_path / "seed7.mcap").write_bytes(data)
    blocks = python_blocks(REPO / "docs" / "RECORDINGS.md")
    assert len(blocks) >= 3, "the reading examples are gone"
    for i, code in enumerate(blocks):
        cuts = [1.0] if "killed.mcap" not in code else [0.13, 0.5, 0.77, 0.9031, 0.999]
        for frac in cuts:
            (tmp_path / "killed.mcap").write_bytes(data[: int(len(data) * frac)])
            out = subprocess.run(
                [sys.executable, "-c", code],
                cwd=tmp_path,
                capture_output=True,
                text=True,
            )
            assert out.returncode == 0, f"block {i} (cut {frac}):\n{code}\n{out.stderr}"
            if "killed.mcap" in code:
                assert "cut short" in out.stdout, out.stdout
                assert "/match/state" in out.stdout, out.stdout
