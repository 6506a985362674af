"""The operator console in Firefox (Debian's firefox-esr), driven over WebDriver BiDi.

Firefox speaks WebDriver BiDi itself (`--remote-debugging-port`), so no geckodriver is needed:
this file is a small BiDi client on the Python `websockets` package. One `rovernav serve` waits
for a plan; the page, in headless Firefox, must refuse without the token, draw the map, take a
goal clicked on the map with real pointer input, run the mission with the rover icon moving,
answer `status` typed with real key input in its log, and show the run's end. The report then
has the clicked goal. The same checks as the Chromium test, in Gecko.

Run by tests/browser/run.sh (ROVERNAV_BIN names the binary).
"""

import json
import math
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

from console_server import START, drain, start_serve, wait
from websockets.sync.client import connect

GOAL = (12.0, 13.0)


class Firefox:
    """Headless Firefox with one browsing context, driven over WebDriver BiDi."""

    def __init__(self, profile):
        binary = shutil.which("firefox-esr") or shutil.which("firefox")
        self.process = subprocess.Popen(
            [binary, "--headless", "--no-remote", "--profile", profile, "--remote-debugging-port", "0"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        # The address comes on a line of Firefox's output; a reader thread looks for it, so a
        # Firefox that never prints it fails the test after 60 s instead of hanging it.
        found = []
        def find():
            for line in self.process.stdout:
                m = re.search(r"WebDriver BiDi listening on (ws://\S+)", line)
                if m:
                    found.append(m.group(1))
                    break
            drain(self.process.stdout)
        threading.Thread(target=find, daemon=True).start()
        url = wait("Firefox's WebDriver BiDi address", lambda: found and found[0])
        self.ws = connect(url + "/session", max_size=None)
        self.next_id = 0
        self.call("session.new", {"capabilities": {}})
        self.context = self.call("browsingContext.getTree", {})["contexts"][0]["context"]
        self.call("browsingContext.setViewport",
                  {"context": self.context, "viewport": {"width": 1400, "height": 1250}})

    def call(self, method, params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self.ws.recv())
            if message.get("id") == self.next_id:
                if message.get("type") != "success":
                    raise AssertionError(f"{method}: {message}")
                return message["result"]

    def get(self, url):
        self.call("browsingContext.navigate", {"context": self.context, "url": url, "wait": "complete"})

    def js(self, expression):
        """The expression's value, through JSON (so arrays and objects come back whole)."""
        result = self.call("script.evaluate", {
            "expression": f"JSON.stringify(({expression}) ?? null)",
            "target": {"context": self.context}, "awaitPromise": False})
        if result.get("type") == "exception":
            raise AssertionError(f"{expression}: {result['exceptionDetails']['text']}")
        return json.loads(result["result"]["value"])

    def click_at(self, x, y):
        """A real mouse click at viewport coordinates."""
        self.call("input.performActions", {"context": self.context, "actions": [{
            "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [{"type": "pointerMove", "x": int(round(x)), "y": int(round(y))},
                        {"type": "pointerDown", "button": 0}, {"type": "pointerUp", "button": 0}]}]})
        self.call("input.releaseActions", {"context": self.context})

    def click(self, selector):
        x, y = self.js(f"""(() => {{ const r = document.querySelector({json.dumps(selector)}).getBoundingClientRect();
            return [r.left + r.width / 2, r.top + r.height / 2]; }})()""")
        self.click_at(x, y)

    def type_keys(self, text):
        """Real key presses; `\\ue007` is Enter."""
        keys = [a for ch in text for a in ({"type": "keyDown", "value": ch}, {"type": "keyUp", "value": ch})]
        self.call("input.performActions", {"context": self.context, "actions": [
            {"type": "key", "id": "keyboard", "actions": keys}]})

    def quit(self):
        try:
            self.call("session.end", {})
        except Exception:
            pass
        self.process.terminate()
        self.process.wait(10)


class ConsoleInFirefox(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="rovernav-firefox-")
        cls.server, cls.url, cls.out = start_serve(cls.tmp, "firefox-test-token")
        cls.base = cls.url.split("/?")[0]
        os.makedirs(os.path.join(cls.tmp, "profile"))
        cls.firefox = Firefox(os.path.join(cls.tmp, "profile"))

    @classmethod
    def tearDownClass(cls):
        cls.firefox.quit()
        if cls.server.poll() is None:
            cls.server.terminate()
            cls.server.wait(10)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_1_without_the_token_the_console_is_refused(self):
        ff = self.firefox
        ff.get(self.base + "/")
        self.assertIn("Access token", ff.js("document.body.innerText"))
        self.assertIsNone(ff.js("document.getElementById('map')"), "no console without the token")

    def test_2_the_map_draws_the_world(self):
        ff = self.firefox
        ff.get(self.url)
        wait("the world", lambda: ff.js("rovernav.state.world && rovernav.map.draws > 0"))
        self.assertEqual(ff.js("rovernav.state.phase"), "waiting")
        spread = ff.js("""(() => { const c = document.getElementById('map').getContext('2d');
            const d = c.getImageData(100, 100, 500, 500).data; const seen = new Set();
            for (let i = 0; i < d.length; i += 4 * 97) seen.add(d[i] >> 4 << 8 | d[i + 1] >> 4 << 4 | d[i + 2] >> 4);
            return seen.size; })()""")
        self.assertGreater(spread, 20, "the terrain's elevation colours are drawn")

    def test_3_a_goal_clicked_on_the_map_runs_and_the_rover_moves(self):
        ff = self.firefox
        goal_at = ff.js(f"""(() => {{
            const rocks = rovernav.map.world.terrain.rocks || [];
            const clear = (px, py) => rocks.every((r) => Math.hypot(r.x - px, r.y - py) - r.diameter / 2 > 1.0);
            for (let d = 0; d <= 4; d += 0.25)
              for (let a = 0; a < 2 * Math.PI; a += d > 0 ? 0.25 / d : 7)
                if (clear({GOAL[0]} + d * Math.cos(a), {GOAL[1]} + d * Math.sin(a)))
                  return [{GOAL[0]} + d * Math.cos(a), {GOAL[1]} + d * Math.sin(a)];
            return [{GOAL[0]}, {GOAL[1]}]; }})()""")
        ff.click('input[value="goal"]')
        # worldToClient is relative to the map canvas; the pointer moves in the viewport.
        ff.click_at(*ff.js(f"""(() => {{ const [x, y] = rovernav.map.worldToClient({goal_at[0]}, {goal_at[1]});
            const r = document.getElementById('map').getBoundingClientRect(); return [r.left + x, r.top + y]; }})()"""))
        draft = ff.js("rovernav.draft")
        self.assertLess(math.dist((draft["goal"]["x"], draft["goal"]["y"]), goal_at), 0.15, draft)
        ff.click("#send")
        wait("the mission to run", lambda: ff.js("rovernav.state.phase") == "running")
        # The run's world (logged at its start) has the goal the console sent: the clicked point,
        # as the page rounded it.
        goal = wait("the run's world", lambda: (lambda g: g if math.dist(
            (g["position"]["x"], g["position"]["y"]), goal_at) < 0.15 else None)(ff.js("rovernav.map.world.goal")))
        first = wait("the rover's pose", lambda: ff.js("rovernav.state.rover"))
        wait("the rover icon to move", lambda: math.dist(
            (first["x"], first["y"]), (lambda p: (p["x"], p["y"]))(ff.js("rovernav.state.rover"))) > 1.0)
        type(self).goal = (goal["position"]["x"], goal["position"]["y"])

    def test_4_status_typed_in_the_command_line_answers_in_the_log(self):
        ff = self.firefox
        ff.click("#cmd")
        ff.type_keys("status\ue007")
        answer = wait("the status answer", lambda: [t for t in ff.js("rovernav.log.texts()")
                                                    if t.startswith("mission running ·") or t.startswith("mission over ·")])
        self.assertIn("goal (", answer[0])

    def test_5_the_run_ends_at_the_clicked_goal(self):
        ff = self.firefox
        wait("the mission's end", lambda: ff.js("rovernav.state.phase") == "done", timeout=240)
        self.server.wait(60)
        with open(os.path.join(self.out, "report.json")) as f:
            report = json.load(f)
        self.assertEqual(report["outcome"], "reached", report["message"])
        self.assertAlmostEqual(report["straight_line_m"], math.dist(START, self.goal), places=6)
        self.assertEqual(ff.js("rovernav.state.outcome"), "reached")


if __name__ == "__main__":
    unittest.main(verbosity=2)
