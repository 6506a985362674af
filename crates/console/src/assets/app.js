// The console's connection and the glue between messages and panels. `window.rovernav` exposes
// the state (the browser tests read it).
"use strict";

function esc(s) { return String(s).replace(/[<>&"]/g, (c) => ({ "<": "&lt;", ">": "&gt;", "&": "&amp;", '"': "&quot;" })[c]); }

const token = new URLSearchParams(location.search).get("token") || "";
const map = new RoverMap(el("map"));
const log = new Log(el("log"), el("logfilter"));
const state = {
  connected: false, client: null, holder: null, phase: "-", outcome: null, replay: null,
  channels: {}, world: false, rover: null, cycles: 0, simTime: null, messages: 0, lagged: 0,
  components: {}, power: null, cameras: {}, closed: null, frames: 0,
};
const busFrames = new Map();
const draft = { waypoints: [], goal: null, keep_out: [], zone: [] };
let ws = null, dirty = true;

function send(obj) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(obj));
}
const commandLine = new CommandLine(el("cmd"), el("completion"), (line) => send({ type: "command", line }));

function setBadge(id, text, cls) { const b = el(id); b.textContent = text; b.className = "badge " + (cls || ""); }

function showRole() {
  const me = state.client !== null && state.holder === state.client;
  if (state.replay) setBadge("role", "replay", "warn");
  else setBadge("role", me ? "you command" : state.holder ? `watching (client ${state.holder} commands)` : "watching", me ? "ok" : "warn");
  el("take").disabled = me || !!state.replay;
}

function showPhase() {
  const cls = { running: "ok", waiting: "warn", done: "", replay: "warn" }[state.phase] || "";
  setBadge("phase", state.phase === "done" ? `done: ${state.outcome}` : state.phase, cls);
}

function onTelemetry(topic, t, data) {
  state.messages++;
  if (topic === "/sim/world") {
    map.setWorld(data); state.world = true;
  } else if (topic === "/sim/truth") {
    map.truth.push({ x: data.pose.x, y: data.pose.y, yaw: data.pose.yaw });
    state.rover = { x: data.pose.x, y: data.pose.y, yaw: data.pose.yaw };
    state.cycles = data.cycle; state.simTime = data.sim_time_s;
    if (state.pending && state.pending.cycle === data.cycle) { map.addClouds(state.pending.clouds, data.pose); state.pending = null; }
  } else if (topic === "/localization/estimate") {
    map.estimates.push({ x: data.pose.x, y: data.pose.y });
    state.estimate = data.pose;
  } else if (topic === "/bus/platform/frame") {
    // Frames logged on the bus; `/platform/sensor_frame` then ties one to its cycle by number.
    busFrames.set(data.seq, data.frame || data);
    if (busFrames.size > 64) busFrames.delete(busFrames.keys().next().value);
  } else if (topic === "/platform/sensor_frame") {
    const frame = data.frame || (data.clouds !== undefined ? data : busFrames.get(data.bus_seq));
    if (frame) onFrame(data.cycle, frame);
  } else if (topic === "/log") {
    const kind = (data.level || 0) >= 3 ? "error" : "event";
    log.add(kind, `${data.name ? data.name + ": " : ""}${data.message}`);
  } else if (topic === "/navigation/plan") {
    map.plan = data.points || [];
  } else if (topic === "/sim/hazard_contacts") {
    map.contacts.push({ x: data.x, y: data.y });
    log.add("error", `hazard contact ${data.contacts} at (${fmt(data.x)}, ${fmt(data.y)}): ${data.cause}`);
  } else if (topic === "/executive/report") {
    log.add("event", `report: ${data.outcome} (${data.message}); driven ${fmt(data.distance_driven_m, 1)} m; goal error ${fmt(data.goal_error_m)} m`);
  } else if (topic === "/bus/system/status") {
    state.components[data.component] = { state: data.state, message: data.message };
    el("components").innerHTML = componentRows(state.components);
  } else if (topic === "/power" || topic.endsWith("/power")) {
    state.power = data;
  } else if (topic.startsWith("/camera/")) {
    state.cameras[topic] = data;
    const sel = el("camsel");
    if (![...sel.options].some((o) => o.value === topic)) sel.add(new Option(topic.slice(8), topic));
    if (sel.value === topic) showCamera();
  }
  dirty = true;
}

// One sensor frame: sensed ground, proximity, attitude, encoders, power.
function onFrame(cycle, frame) {
  if (frame.clouds && frame.clouds.length) {
    // Placed with the truth of the same cycle, which follows in the log.
    if (cycle === 0 && map.truth.length === 0 && map.world) map.addClouds(frame.clouds, map.world.start);
    else state.pending = { cycle, clouds: frame.clouds };
  }
  map.proximity = frame.proximity;
  const imu = frame.imu && frame.imu.length ? frame.imu[frame.imu.length - 1] : null;
  if (imu) {
    const compass = Number.isFinite(imu.compass_yaw);
    state.attitude = { yaw: compass ? imu.compass_yaw : (state.rover || {}).yaw || 0, pitch: imu.incl_pitch, roll: imu.incl_roll, source: compass ? "compass" : "estimate" };
  }
  const enc = encoderHtml(frame.odometry);
  if (enc) el("encoders").innerHTML = enc;
  if (frame.power) state.power = frame.power;
  if (frame.motion_stopped) log.add("event", `cycle ${cycle}: motion stopped: ${frame.motion_stopped}`);
  state.frames++;
}

function showCamera() {
  const img = state.cameras[el("camsel").value];
  if (img && img.format) {
    // foxglove.CompressedImage: PNG or JPEG bytes.
    const pic = new Image();
    pic.onload = () => { const c = el("camera"); c.width = pic.width; c.height = pic.height; c.getContext("2d").drawImage(pic, 0, 0); };
    pic.src = `data:image/${img.format === "jpeg" ? "jpeg" : "png"};base64,${img.data}`;
    el("caminfo").textContent = `${img.frame_id} (${img.format}) at t = ${fmt(img.timestamp.sec + img.timestamp.nsec / 1e9, 1)} s`;
  } else if (img && drawImage(el("camera"), img)) {
    el("caminfo").textContent = `${img.frame_id} ${img.width}x${img.height} ${img.encoding} at t = ${img.timestamp.sec}.${String(img.timestamp.nsec).padStart(9, "0").slice(0, 1)} s`;
  }
}

function onMessage(text) {
  let m;
  try { m = JSON.parse(text); } catch (e) { return; }
  switch (m.type) {
    case "hello":
      state.client = m.client; state.holder = m.holder; state.phase = m.phase.phase; state.outcome = m.phase.outcome;
      state.replay = m.replay; commandLine.setHelp(m.help);
      el("replaybar").hidden = !m.replay;
      log.add("event", `connected as client ${m.client}`);
      showRole(); showPhase();
      break;
    case "channel": state.channels[m.id] = m.topic; break;
    case "msg": { const topic = state.channels[m.ch]; if (topic) onTelemetry(topic, m.t, m.data); break; }
    case "lagged": state.lagged += m.skipped; log.add("error", `this console fell behind: ${m.skipped} messages skipped`); break;
    case "command": log.add("command", `[client ${m.client}] > ${m.line}`); break;
    case "reply": log.add("reply", m.text); break;
    case "error": log.add("error", m.text); break;
    case "authority":
      state.holder = m.holder; showRole();
      log.add("event", m.holder ? `client ${m.holder} holds command authority` : "nobody holds command authority");
      break;
    case "phase":
      state.phase = m.phase; state.outcome = m.outcome; showPhase();
      log.add("event", `phase: ${m.phase}${m.outcome ? " (" + m.outcome + ")" : ""}`);
      break;
    case "reset":
      map.reset(); busFrames.clear(); state.components = {}; state.pending = null; state.rover = null; break;
    case "time": {
      const r = state.replay; state.simTime = m.t_ns / 1e9;
      el("scrub").value = r.end_ns > r.start_ns ? Math.round(1000 * (m.t_ns - r.start_ns) / (r.end_ns - r.start_ns)) : 1000;
      el("rtime").textContent = `${fmt(m.t_ns / 1e9, 1)} / ${fmt(r.end_ns / 1e9, 1)} s`;
      el("play").textContent = m.playing ? "Pause" : "Play"; state.playing = m.playing;
      break;
    }
  }
}

function connect() {
  const url = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws?token=${encodeURIComponent(token)}`;
  ws = new WebSocket(url);
  ws.onopen = () => { state.connected = true; setBadge("conn", "connected", "ok"); };
  ws.onmessage = (e) => onMessage(e.data);
  ws.onclose = (e) => {
    state.connected = false; state.closed = { code: e.code, reason: e.reason };
    setBadge("conn", "disconnected", "bad");
    log.add("error", `connection closed (${e.code}${e.reason ? ": " + e.reason : ""}); reload the page to reconnect`);
  };
}

// The mission planner.
function planText() {
  const p = (q) => `(${fmt(q.x, 1)}, ${fmt(q.y, 1)})`;
  el("plantext").textContent = draft.waypoints.length || draft.goal || draft.keep_out.length || draft.zone.length
    ? `plan: ${draft.waypoints.map(p).join(" -> ") || "no waypoint"}; goal ${draft.goal ? p(draft.goal) : "(unchanged)"}; ${draft.keep_out.length} keep-out zone(s)${draft.zone.length ? ` + ${draft.zone.length} vertices open` : ""}`
    : "";
  dirty = true;
}
el("map").addEventListener("click", (e) => {
  if (!map.world || state.replay) return;
  const [x, y] = map.clientToWorld(e), p = { x: Math.round(x * 100) / 100, y: Math.round(y * 100) / 100 };
  const tool = document.querySelector('input[name="tool"]:checked').value;
  if (tool === "waypoint") draft.waypoints.push(p);
  else if (tool === "goal") draft.goal = p;
  else draft.zone.push(p);
  planText();
});
el("closezone").onclick = () => { if (draft.zone.length >= 3) draft.keep_out.push(draft.zone); draft.zone = []; planText(); };
el("clearplan").onclick = () => { draft.waypoints = []; draft.goal = null; draft.keep_out = []; draft.zone = []; planText(); };
el("send").onclick = () => {
  if (!map.world) return;
  const xy = (p) => [p.x, p.y];
  let goal = draft.goal, waypoints = draft.waypoints.slice();
  // Waypoints without a goal: the last one is the goal.
  if (!goal && waypoints.length) goal = waypoints.pop();
  if (!goal) goal = map.world.goal.position;
  send({ type: "plan", goal: xy(goal), waypoints: waypoints.map(xy), keep_out: draft.keep_out.map((z) => z.map(xy)) });
  log.add("event", `plan sent: ${waypoints.length} waypoint(s), goal (${fmt(goal.x, 1)}, ${fmt(goal.y, 1)})`);
  el("clearplan").onclick();
};
el("pause").onclick = () => send({ type: "command", line: "mission pause" });
el("resume").onclick = () => send({ type: "command", line: "mission start" });
el("abort").onclick = () => { if (confirm("Abort the mission?")) send({ type: "command", line: "mission abort" }); };
el("take").onclick = () => send({ type: "take_control" });
el("camsel").onchange = showCamera;
el("navcam").onclick = () => {
  const angle = (id, limit, otherwise) => { const v = parseFloat(el(id).value); return Number.isFinite(v) ? Math.max(-limit, Math.min(limit, v)) : otherwise; };
  send({ type: "command", line: `navcam ${angle("navpan", 180, 0)} ${angle("navtilt", 90, -20)}` });
};
document.querySelectorAll("#pad button, #motors button").forEach((b) => {
  b.onclick = () => {
    const step = Math.max(0.1, Math.min(5, parseFloat(el("step").value) || 0.5));
    b.dataset.cmd.split(";").forEach((line) => send({ type: "command", line: line.replace("STEP", step) }));
  };
});
el("play").onclick = () => send(state.playing ? { type: "pause" } : { type: "play", speed: parseFloat(el("rspeed").value) });
el("scrub").oninput = () => {
  const r = state.replay;
  if (r) send({ type: "seek", t_ns: Math.round(r.start_ns + (r.end_ns - r.start_ns) * el("scrub").value / 1000) });
};

function frame() {
  if (dirty) {
    dirty = false;
    map.draw(draft);
    if (state.attitude) { drawCompass(el("compass"), state.attitude); el("attitude").innerHTML = attitudeText(state.attitude); }
    el("simtime").textContent = state.simTime === null ? "t = -" : `t = ${fmt(state.simTime, 1)} s, cycle ${state.cycles}`;
    el("power").innerHTML = state.power ? powerHtml(state.power) : "no power data";
  }
  requestAnimationFrame(frame);
}
drawCompass(el("compass"), null);
(() => {
  const c = el("camera").getContext("2d");
  c.fillStyle = "#777"; c.font = "14px sans-serif";
  c.fillText("no camera image yet", 20, 30);
})();
window.rovernav = { state, map, log, draft, send };
connect();
requestAnimationFrame(frame);
