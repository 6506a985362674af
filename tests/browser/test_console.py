"""The operator console in a real browser (Debian's chromium and chromedriver, Python selenium).

One `rovernav serve` holds the default mission for a plan; a commanding browser and a watching
one talk to it: the page refuses without the token, draws the map, plans a mission by clicks,
watches the rover move, answers `status` in its log, and the watcher cannot command. The run's
report.json then shows the clicked goal (its straight-line distance from the start).

Run by tests/browser/run.sh (ROVERNAV_BIN names the binary); ROVERNAV_SCREENSHOT=PATH saves the
finished console's screenshot there (docs/images/console.png is the README's).
"""

import json
import math
import os
import shutil
import tempfile
import time
import unittest
import urllib.error
import urllib.request

from console_server import START, start_serve, wait
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys

FLAGS = ("--headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
         "--disable-background-networking --disable-component-update --disable-sync").split()
WAYPOINT = (8.0, 9.0)
GOAL = (12.0, 13.0)
KEEP_OUT = [(16.0, 4.0), (19.0, 4.0), (17.5, 7.0)]  # off the way, so the run is unchanged by it


def browser(user_dir):
    options = webdriver.ChromeOptions()
    for flag in FLAGS + ["--window-size=1400,1250", "--user-data-dir=" + user_dir]:
        options.add_argument(flag)
    options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    service = Service(shutil.which("chromedriver") or "/usr/bin/chromedriver")
    return webdriver.Chrome(options=options, service=service)


class ConsoleInABrowser(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="rovernav-browser-")
        cls.server, cls.url, cls.out = start_serve(cls.tmp, "browser-test-token")
        cls.base = cls.url.split("/?")[0]
        cls.commander = browser(os.path.join(cls.tmp, "chrome-a"))
        cls.watcher = None

    @classmethod
    def tearDownClass(cls):
        for d in (cls.commander, cls.watcher):
            if d is not None:
                d.quit()
        if cls.server.poll() is None:
            cls.server.terminate()
            cls.server.wait(10)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def js(self, expr, driver=None):
        return (driver or self.commander).execute_script("return " + expr)

    def log_texts(self, driver=None):
        return self.js("rovernav.log.texts()", driver)

    def test_1_without_the_token_the_console_is_refused(self):
        with self.assertRaises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(self.base + "/")
        self.assertEqual(refused.exception.code, 401)
        self.commander.get(self.base + "/")
        self.assertIn("Access token", self.commander.page_source)
        self.assertEqual(self.commander.find_elements(By.ID, "map"), [], "no console without the token")
        with self.assertRaises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(self.base + "/ws?token=wrong")
        self.assertEqual(refused.exception.code, 401)

    def test_2_the_map_draws_the_world(self):
        self.commander.get(self.url)
        wait("the world", lambda: self.js("rovernav.state.world && rovernav.map.draws > 0"))
        self.assertEqual(self.js("rovernav.state.phase"), "waiting")
        self.assertEqual(self.js("rovernav.state.holder"), self.js("rovernav.state.client"), "first come commands")
        # The terrain is drawn in colours: the map's pixels are far from uniform.
        spread = self.js("""(() => { const c = document.getElementById('map').getContext('2d');
            const d = c.getImageData(100, 100, 500, 500).data; const seen = new Set();
            for (let i = 0; i < d.length; i += 4 * 97) seen.add(d[i] >> 4 << 8 | d[i + 1] >> 4 << 4 | d[i + 2] >> 4);
            return seen.size; })()""")
        self.assertGreater(spread, 20, "the terrain's elevation colours are drawn")

    def click_world(self, x, y):
        canvas = self.commander.find_element(By.ID, "map")
        cx, cy = self.js(f"rovernav.map.worldToClient({x}, {y})")
        rect = canvas.rect
        ActionChains(self.commander).move_to_element_with_offset(
            canvas, cx - rect["width"] / 2, cy - rect["height"] / 2).click().perform()

    def clear_of_rocks(self, x, y):
        """The point nearest (x, y) at least 1 m clear of every rock (from the world message)."""
        return self.js(f"""(() => {{
            const rocks = rovernav.map.world.terrain.rocks || [];
            const clear = (px, py) => rocks.every((r) => Math.hypot(r.x - px, r.y - py) - r.diameter / 2 > 1.0);
            for (let d = 0; d <= 4; d += 0.25)
              for (let a = 0; a < 2 * Math.PI; a += d > 0 ? 0.25 / d : 7)
                if (clear({x} + d * Math.cos(a), {y} + d * Math.sin(a))) return [{x} + d * Math.cos(a), {y} + d * Math.sin(a)];
            return [{x}, {y}]; }})()""")

    def test_3_a_clicked_plan_starts_the_mission_and_the_rover_moves(self):
        waypoint, goal_at = self.clear_of_rocks(*WAYPOINT), self.clear_of_rocks(*GOAL)
        self.commander.find_element(By.CSS_SELECTOR, 'input[value="waypoint"]').click()
        self.click_world(*waypoint)
        self.commander.find_element(By.CSS_SELECTOR, 'input[value="goal"]').click()
        self.click_world(*goal_at)
        draft = self.js("rovernav.draft")
        self.assertEqual(len(draft["waypoints"]), 1)
        self.assertLess(math.dist((draft["goal"]["x"], draft["goal"]["y"]), goal_at), 0.15, draft)
        self.commander.find_element(By.CSS_SELECTOR, 'input[value="keepout"]').click()
        for vertex in KEEP_OUT:
            self.click_world(*vertex)
        self.commander.find_element(By.ID, "closezone").click()
        self.commander.find_element(By.ID, "send").click()
        wait("the mission to run", lambda: self.js("rovernav.state.phase") == "running")
        # The run's world (logged at its start) has the plan in it.
        goal = wait("the run's world", lambda: (lambda g: g if math.dist(
            (g["position"]["x"], g["position"]["y"]), goal_at) < 0.15 else None)(self.js("rovernav.map.world.goal")))
        self.assertEqual(len(goal["waypoints"]), 1)
        self.assertEqual(len(goal["keep_out"]), 1, "the drawn keep-out zone is the mission's")
        self.assertLess(math.dist((goal["keep_out"][0][0]["x"], goal["keep_out"][0][0]["y"]), KEEP_OUT[0]), 0.15)
        first = wait("the rover's pose", lambda: self.js("rovernav.state.rover"))
        wait("the rover icon to move", lambda: math.dist(
            (first["x"], first["y"]), (lambda p: (p["x"], p["y"]))(self.js("rovernav.state.rover"))) > 1.0)
        self.assertGreater(self.js("rovernav.map.sensedCount"), 0, "sensed ground is drawn")
        type(self).goal = (goal["position"]["x"], goal["position"]["y"])

    def test_4_status_in_the_command_line_answers_in_the_log(self):
        line = self.commander.find_element(By.ID, "cmd")
        line.send_keys("stat", Keys.TAB)
        self.assertEqual(line.get_attribute("value").strip(), "status", "Tab completes from `help`")
        line.send_keys(Keys.ENTER)
        answer = wait("the status answer", lambda: [t for t in self.log_texts() if t.startswith("mission running ·")])
        self.assertIn("goal (", answer[0])

    def test_5_a_second_client_watches_but_cannot_command(self):
        type(self).watcher = browser(os.path.join(self.tmp, "chrome-b"))
        w = self.watcher
        w.get(self.url)
        wait("the watcher's world", lambda: self.js("rovernav.state.world", w))
        self.assertNotEqual(self.js("rovernav.state.holder", w), self.js("rovernav.state.client", w))
        self.assertIn("watching", w.find_element(By.ID, "role").text)
        wait("the path so far", lambda: self.js("rovernav.map.truth.length", w) > 1)
        cmd = w.find_element(By.ID, "cmd")
        cmd.send_keys("mission abort", Keys.ENTER)
        wait("the refusal", lambda: [t for t in self.log_texts(w) if "holds command authority" in t])
        time.sleep(1.0)
        self.assertEqual(self.js("rovernav.state.phase", w), "running", "the watcher's abort did nothing")
        self.assertFalse([t for t in self.log_texts() if t.startswith("mission aborted")])

    def test_6_manual_driving_while_paused(self):
        def press(key):
            self.commander.find_element(By.ID, key).click()

        press("pause")
        wait("the pause", lambda: [t for t in self.log_texts() if t.startswith("mission paused")])
        self.commander.find_element(By.CSS_SELECTOR, '#pad button[data-cmd="turn 45"]').click()
        answer = wait("the turn's answer", lambda: [t for t in self.log_texts() if t.startswith("`turn 45") and "completed" in t])
        self.commander.find_element(By.CSS_SELECTOR, '#pad button[data-cmd="turn -45"]').click()
        wait("the turn back", lambda: [t for t in self.log_texts() if t.startswith("`turn -45") and "completed" in t])
        # The science pair: the Navcam button takes a stereo pair and the camera panel can show it.
        press("navcam")
        pair = wait("the pair's answer", lambda: [t for t in self.log_texts() if t.startswith("`navcam 0 -20` completed")])
        self.assertIn("2 images (navcam_left", pair[0])
        wait("the pair in the camera list", lambda: self.js("[...document.getElementById('camsel').options].some((o) => o.text.includes('navcam'))"))
        press("resume")
        turned = float(answer[0].split("completed: ")[1].split(" deg")[0])
        self.assertAlmostEqual(turned, 45.0, delta=5.0, msg=answer[0])
        wait("the resumed mission", lambda: [t for t in self.log_texts() if t.startswith("mission resumed")])

    def test_7_the_report_has_the_clicked_goal(self):
        state = wait("the mission's end", lambda: self.js("rovernav.state.phase") == "done", timeout=240)
        self.assertTrue(state)
        # The screenshot goes beside the run's outputs; ROVERNAV_SCREENSHOT=docs/images/console.png
        # refreshes the README's picture.
        shot = os.environ.get("ROVERNAV_SCREENSHOT") or os.path.join(self.tmp, "console.png")
        os.makedirs(os.path.dirname(os.path.abspath(shot)), exist_ok=True)
        self.commander.save_screenshot(shot)
        self.server.wait(60)
        with open(os.path.join(self.out, "report.json")) as f:
            report = json.load(f)
        self.assertEqual(report["outcome"], "reached", report["message"])
        # The goal the run was scored against is the clicked one.
        self.assertAlmostEqual(report["straight_line_m"], math.dist(START, self.goal), places=6)
        self.assertEqual(self.js("rovernav.state.outcome"), "reached")


if __name__ == "__main__":
    unittest.main(verbosity=2)
