#!/usr/bin/env python3
"""Checks a rovernav run's telemetry.mcap with an independent reader (the `mcap` package).

Foxglove shows a log natively when its channels carry Foxglove's well-known schemas. This
script opens the log and checks, without any rovernav code:

- every channel has a JSON Schema (encoding `jsonschema`) that is a non-empty object; the
  Foxglove channels are named as Foxglove names its schemas (`foxglove.FrameTransform`,
  `foxglove.Grid`, `foxglove.SceneUpdate`, `foxglove.Log`, and `foxglove.CompressedImage` on
  camera topics) and every message validates against its channel's schema (with the
  `jsonschema` package when installed);
- every cycle (each `/executive/cycle` marker) has a `/tf` and a `/sim/tf` transform, a scene
  update on `/navigation/scene` and `/sim/scene`, and a `/log` line, at the cycle's time;
- both grids come after every cycle whose sensor frame brought range data;
- each sensor frame is logged once (the cycle's message points at the bus frame);
- optionally, the file is at most `--max-bytes`, and every topic the Foxglove layout
  (`--layout docs/foxglove/rovernav-layout.json`) shows is in the log (camera topics aside
  when the run took no images).

Usage: python3 tests/foxglove/check_mcap.py RUN_DIR/telemetry.mcap [--max-bytes N] [--layout FILE]
"""

import argparse
import base64
import json
import os
import struct
import sys
from collections import defaultdict

from mcap.reader import make_reader

try:
    import jsonschema
except ImportError:  # the check then covers the required fields only
    jsonschema = None

FOXGLOVE = {
    "/tf": "foxglove.FrameTransform",
    "/sim/tf": "foxglove.FrameTransform",
    "/map/belief": "foxglove.Grid",
    "/map/traversability": "foxglove.Grid",
    "/navigation/scene": "foxglove.SceneUpdate",
    "/sim/scene": "foxglove.SceneUpdate",
    "/log": "foxglove.Log",
}
PER_CYCLE = ["/tf", "/sim/tf", "/navigation/scene", "/sim/scene", "/log"]
# Fields Foxglove reads, per schema (checked even without the jsonschema package).
REQUIRED = {
    "foxglove.FrameTransform": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"],
    "foxglove.Grid": ["timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride",
                      "cell_stride", "fields", "data"],
    "foxglove.SceneUpdate": ["deletions", "entities"],
    "foxglove.Log": ["timestamp", "level", "message", "name"],
    "foxglove.CompressedImage": ["timestamp", "frame_id", "data", "format"],
}


def fail(message):
    print(f"check_mcap: FAIL: {message}")
    sys.exit(1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log")
    parser.add_argument("--max-bytes", type=int, default=None)
    parser.add_argument("--layout", default=None)
    args = parser.parse_args()
    if not os.path.isfile(args.log):
        fail(f"{args.log}: no such file")
    size = os.path.getsize(args.log)
    if args.max_bytes is not None and size > args.max_bytes:
        fail(f"{args.log}: {size} bytes, more than {args.max_bytes}")

    schemas = {}  # topic -> (name, parsed schema)
    messages = defaultdict(list)  # topic -> [(log_time, data bytes)]
    with open(args.log, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            fail("the log has no summary (not finished)")
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            if schema is None:
                fail(f"{channel.topic}: no schema")
            if schema.encoding != "jsonschema" or channel.message_encoding != "json":
                fail(f"{channel.topic}: schema {schema.encoding}, messages {channel.message_encoding}")
            parsed = json.loads(schema.data)
            if not isinstance(parsed, dict) or not parsed or not (parsed.get("properties") or parsed.get("description")):
                fail(f"{channel.topic}: empty JSON schema {parsed!r}")
            schemas[channel.topic] = (schema.name, parsed)
        for schema, channel, message in reader.iter_messages():
            messages[channel.topic].append((message.log_time, message.data))

    for topic, name in FOXGLOVE.items():
        if topic not in schemas:
            fail(f"{topic}: not in the log")
        if schemas[topic][0] != name:
            fail(f"{topic}: schema {schemas[topic][0]}, expected {name}")
    for topic, (name, _) in schemas.items():
        if topic.startswith("/camera/") and name != "foxglove.CompressedImage":
            fail(f"{topic}: schema {name}, expected foxglove.CompressedImage")

    validated = 0
    for topic, (name, schema) in schemas.items():
        validator = jsonschema.validators.validator_for(schema)(schema) if jsonschema else None
        for _, data in messages[topic]:
            value = json.loads(data)
            for field in REQUIRED.get(name, []):
                if field not in value:
                    fail(f"{topic}: a message without `{field}`")
            if validator is not None:
                errors = list(validator.iter_errors(value))
                if errors:
                    fail(f"{topic}: {errors[0].message}")
            validated += 1
    for topic in PER_CYCLE:
        if not messages[topic]:
            fail(f"{topic}: no messages")

    cycles = [(t, json.loads(d)) for t, d in messages["/executive/cycle"]]
    if len(cycles) < 2:
        fail(f"{len(cycles)} cycles")
    times = {topic: {t for t, _ in messages[topic]} for topic in FOXGLOVE}
    for t, cycle in cycles:
        for topic in PER_CYCLE:
            if t not in times[topic]:
                fail(f"{topic}: nothing in cycle {cycle['cycle']} (log time {t})")

    # Frames once, and the grids after every cycle that brought range data.
    bus = {json.loads(d)["seq"]: json.loads(d)["frame"] for _, d in messages["/bus/platform/frame"]}
    frame_msgs = [(t, json.loads(d)) for t, d in messages["/platform/sensor_frame"]]
    if len(frame_msgs) != len(cycles):
        fail(f"{len(frame_msgs)} sensor frame messages for {len(cycles)} cycles")
    sensing = []
    for t, m in frame_msgs:
        if "frame" in m and "bus_seq" in m:
            fail(f"cycle {m['cycle']}: its frame is logged twice")
        frame = m["frame"] if "frame" in m else bus.get(m.get("bus_seq"))
        if frame is None:
            fail(f"cycle {m['cycle']}: frame {m.get('bus_seq')} not on /bus/platform/frame")
        if m["cycle"] > 0 and frame["clouds"]:
            sensing.append(t)
    for topic in ["/map/belief", "/map/traversability"]:
        for t in sensing:
            if t not in times[topic]:
                fail(f"{topic}: no grid after the range data at log time {t}")
    for topic in ["/map/belief", "/map/traversability"]:
        for _, data in messages[topic]:
            grid = json.loads(data)
            cells = base64.b64decode(grid["data"])
            if not cells or len(cells) % grid["row_stride"] or grid["row_stride"] != grid["column_count"] * grid["cell_stride"]:
                fail(f"{topic}: {len(cells)} bytes are not whole rows of {grid['column_count']} cells")

    images = 0
    for topic, (name, _) in schemas.items():
        if name != "foxglove.CompressedImage":
            continue
        for _, data in messages[topic]:
            image = json.loads(data)
            png = base64.b64decode(image["data"])
            if image["format"] != "png" or png[:8] != b"\x89PNG\r\n\x1a\n" or png[12:16] != b"IHDR":
                fail(f"{topic}: not a PNG")
            width, height = struct.unpack(">II", png[16:24])
            if width == 0 or height == 0:
                fail(f"{topic}: a {width}x{height} PNG")
            images += 1

    layout_topics = check_layout(args.layout, schemas) if args.layout else []

    print(
        f"check_mcap: ok: {args.log}: {size} bytes, {len(schemas)} channels with JSON schemas, "
        f"{validated} messages {'validated' if jsonschema else 'checked'}, {len(cycles)} cycles each with "
        f"{', '.join(PER_CYCLE)}; grids after all {len(sensing)} sensing cycles; {images} PNG images"
        + (f"; the layout's {len(layout_topics)} topics are in the log" if args.layout else "")
    )


def check_layout(path, schemas):
    """Every topic a panel of the layout shows is a channel of the log."""
    with open(path) as f:
        layout = json.load(f)
    wanted = set()
    for panel, config in layout["configById"].items():
        wanted.update(config.get("topics", {}).keys())
        for series in config.get("paths", []):
            wanted.add(series["value"].split(".")[0])
        if "topicToRender" in config:
            wanted.add(config["topicToRender"])
        image = config.get("imageMode", {}).get("imageTopic")
        if image and any(t.startswith("/camera/") for t in schemas):
            wanted.add(image)
    missing = sorted(t for t in wanted if t not in schemas)
    if missing:
        fail(f"{path}: the layout shows topics the log does not have: {missing}")
    return sorted(wanted)


if __name__ == "__main__":
    main()
