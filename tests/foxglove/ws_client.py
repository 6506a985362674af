#!/usr/bin/env python3
"""An independent Foxglove WebSocket client (the `websockets` package) against rovernav's server.

It speaks the `foxglove.websocket.v1` subprotocol as Foxglove does: reads `serverInfo` and the
`advertise`d channels, subscribes to topics, decodes the binary message-data frames (opcode
0x01, subscription id u32 LE, timestamp u64 LE, JSON payload) and validates every payload
against the JSON Schema its channel advertised (with the `jsonschema` package; without it, the
schema's required fields and top-level properties are checked). It also checks that a
connection without the token is refused and that a malformed message closes only that
connection.

Usage: python3 tests/foxglove/ws_client.py URL [--topic /tf ...] [--count N]
  URL is ws://HOST:PORT/?token=TOKEN (what `rovernav serve --foxglove` and the
  `foxglove_replay` example print).
With --serve LOG.mcap it starts `cargo run --release -p rovernav-console --example
foxglove_replay -- LOG.mcap` itself and uses the URL it prints. With --rovernav BIN it starts
`BIN serve [--mission FILE] --foxglove 127.0.0.1:PORT --token-file F --speed 20
--exit-when-done` (the issue's command-line contract) and watches the live run.
"""

import argparse
import asyncio
import json
import os
import shutil
import struct
import subprocess
import socket
import sys
import tempfile
import time
import urllib.parse

import websockets

try:
    import jsonschema
except ImportError:
    jsonschema = None

SUBPROTOCOL = "foxglove.websocket.v1"
# Files and folders this script made, removed at the end.
TEMPORARY = []


def fail(message):
    print(f"ws_client: FAIL: {message}")
    sys.exit(1)


def check_against(schema, value, topic):
    if jsonschema is not None:
        errors = list(jsonschema.validators.validator_for(schema)(schema).iter_errors(value))
        if errors:
            fail(f"{topic}: payload does not fit its advertised schema: {errors[0].message}")
        return
    for field in schema.get("required", []):
        if field not in value:
            fail(f"{topic}: payload without required field `{field}`")
    props = schema.get("properties", {})
    if props and not set(value) <= set(props) | {"$schema"}:
        fail(f"{topic}: payload fields {sorted(set(value) - set(props))} not in the schema")


async def connect(url):
    return await websockets.connect(url, subprotocols=[SUBPROTOCOL], max_size=None, open_timeout=20)


async def refused_without_token(url):
    parts = urllib.parse.urlsplit(url)
    bare = urllib.parse.urlunsplit((parts.scheme, parts.netloc, parts.path or "/", "", ""))
    try:
        ws = await connect(bare)
    except websockets.exceptions.InvalidStatus as e:
        if e.response.status_code != 401:
            fail(f"without the token: HTTP {e.response.status_code}, expected 401")
        return
    await ws.close()
    fail("a connection without the token was accepted")


async def bad_message_closes_only_that_connection(url):
    ws = await connect(url)
    await ws.send('{"op": "subscribe", "subscriptions": [')
    try:
        while True:
            await asyncio.wait_for(ws.recv(), timeout=20)
    except websockets.exceptions.ConnectionClosed as e:
        code = e.rcvd.code if e.rcvd else None
        if code not in (1003, 1007, 1008):
            fail(f"a malformed message closed with {code}, expected 1007")
        return
    fail("a malformed message did not close the connection")


async def watch(url, topics, count):
    ws = await connect(url)
    if ws.subprotocol != SUBPROTOCOL:
        fail(f"server chose subprotocol {ws.subprotocol!r}")
    info = json.loads(await asyncio.wait_for(ws.recv(), timeout=20))
    if info.get("op") != "serverInfo":
        fail(f"first message is {info.get('op')!r}, expected serverInfo")
    channels = {}
    subs = {}
    received = {t: 0 for t in topics}
    next_id = 0
    deadline = asyncio.get_running_loop().time() + 120
    while any(n < count for n in received.values()):
        left = deadline - asyncio.get_running_loop().time()
        if left <= 0:
            fail(f"timed out: received {received}")
        msg = await asyncio.wait_for(ws.recv(), timeout=left)
        if isinstance(msg, str):
            m = json.loads(msg)
            if m.get("op") == "advertise":
                new = []
                for c in m["channels"]:
                    for key in ("id", "topic", "encoding", "schemaName", "schema", "schemaEncoding"):
                        if key not in c:
                            fail(f"advertised channel without `{key}`: {c}")
                    if c["encoding"] != "json" or c["schemaEncoding"] != "jsonschema":
                        fail(f"{c['topic']}: encoding {c['encoding']}, schema {c['schemaEncoding']}")
                    schema = json.loads(c["schema"])
                    if not schema:
                        fail(f"{c['topic']}: empty schema")
                    channels[c["id"]] = (c["topic"], c["schemaName"], schema)
                    if c["topic"] in topics and c["topic"] not in subs.values():
                        subs[next_id] = c["topic"]
                        new.append({"id": next_id, "channelId": c["id"]})
                        next_id += 1
                if new:
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
            continue
        if len(msg) < 13 or msg[0] != 0x01:
            fail(f"binary frame with opcode {msg[0] if msg else None}, expected 0x01")
        sub, t = struct.unpack_from("<IQ", msg, 1)
        if sub not in subs:
            fail(f"message for unknown subscription {sub}")
        topic = subs[sub]
        schema = next(s for (tp, _, s) in channels.values() if tp == topic)
        check_against(schema, json.loads(msg[13:]), topic)
        received[topic] += 1
    await ws.close()
    names = {tp: name for (tp, name, _) in channels.values()}
    return received, names


async def main_async(url, topics, count):
    await refused_without_token(url)
    await bad_message_closes_only_that_connection(url)
    received, names = await watch(url, topics, count)
    summary = ", ".join(f"{t} ({names[t]}): {n}" for t, n in received.items())
    validator = "jsonschema" if jsonschema else "required fields"
    print(f"ws_client: ok: {url.split('?')[0]}: refused without the token, bad client closed alone; "
          f"messages validated ({validator}): {summary}")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_rovernav(binary, mission):
    """`rovernav serve --foxglove` on free loopback ports, with a token file; the URL."""
    token = "ws-client-" + os.urandom(8).hex()
    token_file = tempfile.NamedTemporaryFile("w", suffix=".token", delete=False)
    token_file.write(token + "\n")
    token_file.close()
    fox, console = free_port(), free_port()
    out = tempfile.mkdtemp(prefix="rovernav-ws-client-")
    command = [binary, "serve"] + ([mission] if mission else []) + [
        "--listen", f"127.0.0.1:{console}", "--foxglove", f"127.0.0.1:{fox}",
        "--token-file", token_file.name, "--speed", "20", "--exit-when-done", "--out", out]
    server = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    TEMPORARY.extend([token_file.name, out])
    deadline = time.time() + 60
    while time.time() < deadline:
        if server.poll() is not None:
            fail(f"`{' '.join(command)}` exited {server.returncode}: {server.stderr.read().strip()}")
        try:
            socket.create_connection(("127.0.0.1", fox), timeout=1).close()
            return server, f"ws://127.0.0.1:{fox}/?token={token}"
        except OSError:
            time.sleep(0.1)
    server.kill()
    fail(f"`{' '.join(command)}` did not listen on {fox} within 60 s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("url", nargs="?")
    parser.add_argument("--serve", metavar="LOG.mcap")
    parser.add_argument("--rovernav", metavar="BIN")
    parser.add_argument("--mission", metavar="FILE")
    parser.add_argument("--topic", action="append")
    parser.add_argument("--count", type=int, default=5)
    args = parser.parse_args()
    topics = args.topic or ["/tf", "/navigation/scene", "/log"]
    server = None
    url = args.url
    if args.serve:
        command = ["cargo", "run", "--quiet", "--release", "-p", "rovernav-console", "--example",
                   "foxglove_replay", "--", args.serve, "--listen", "127.0.0.1:0"]
        server = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
        url = server.stdout.readline().strip()
        if not url.startswith("ws://"):
            server.kill()
            fail(f"the replay server printed {url!r}")
    if args.rovernav:
        server, url = start_rovernav(args.rovernav, args.mission)
    if not url:
        fail("give a URL, --serve LOG.mcap or --rovernav BIN")
    try:
        asyncio.run(main_async(url, topics, args.count))
    finally:
        if server is not None:
            server.kill()
            server.wait()
        for path in TEMPORARY:
            shutil.rmtree(path, ignore_errors=True) if os.path.isdir(path) else os.remove(path)


if __name__ == "__main__":
    main()
