"""What both browser tests share: a `rovernav serve` waiting for a plan, and polling."""

import os
import subprocess
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.environ.get("ROVERNAV_BIN", os.path.join(ROOT, "target", "release", "rovernav"))
START = (5.0, 5.0)  # the default mission's start


def drain(stream):
    """Reads a child's output to its end on a thread, so a full pipe never blocks the child."""
    threading.Thread(target=lambda: [None for _ in stream], daemon=True).start()


def wait(what, pred, timeout=60.0):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = pred()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def start_serve(tmp, token):
    """`rovernav serve` of the default mission at 30x, waiting for a plan, its outputs in
    TMP/run; returns the process, the console URL (with the token) and the output folder."""
    out = os.path.join(tmp, "run")
    token_file = os.path.join(tmp, "token")
    with open(token_file, "w") as f:
        f.write(token + "\n")
    server = subprocess.Popen(
        [BIN, "serve", os.path.join(ROOT, "missions", "default.toml"), "--wait", "--speed", "30",
         "--listen", "127.0.0.1:0", "--token-file", token_file, "--out", out, "--exit-when-done"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    url = server.stdout.readline().strip()
    assert url.endswith(f"/?token={token}"), f"first line: {url!r}"
    drain(server.stdout)
    drain(server.stderr)
    return server, url, out
