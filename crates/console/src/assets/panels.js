// The panels beside the map: compass, camera, log and command line, encoders, power, components.
"use strict";

function el(id) { return document.getElementById(id); }
function fmt(v, d) { return Number.isFinite(v) ? v.toFixed(d === undefined ? 2 : d) : "-"; }
function deg(rad) { return rad * 180 / Math.PI; }

// A graphical compass (SR2's mission panel): heading needle, pitch and roll.
function drawCompass(canvas, att) {
  const ctx = canvas.getContext("2d"), w = canvas.width, r = w / 2 - 14, c = w / 2;
  ctx.clearRect(0, 0, w, w);
  ctx.strokeStyle = "#667"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.arc(c, c, r, 0, 2 * Math.PI); ctx.stroke();
  ctx.fillStyle = "#aab"; ctx.font = "12px sans-serif"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
  [["N", 0], ["E", 90], ["S", 180], ["W", 270]].forEach(([l, a]) => {
    const t = a * Math.PI / 180; ctx.fillText(l, c + (r + 8) * Math.sin(t), c - (r + 8) * Math.cos(t));
  });
  if (!att) return;
  // Artificial horizon: tilted by roll, shifted by pitch.
  ctx.save(); ctx.beginPath(); ctx.arc(c, c, r - 4, 0, 2 * Math.PI); ctx.clip();
  ctx.translate(c, c); ctx.rotate(att.roll || 0);
  const shift = Math.max(-r, Math.min(r, deg(att.pitch || 0) * 3));
  ctx.fillStyle = "rgba(150,110,70,0.35)"; ctx.fillRect(-r, shift, 2 * r, 2 * r);
  ctx.restore();
  // Compass heading: clockwise from north (yaw is counter-clockwise from east).
  const heading = Math.PI / 2 - att.yaw;
  ctx.strokeStyle = "#f55"; ctx.lineWidth = 3;
  ctx.beginPath(); ctx.moveTo(c, c); ctx.lineTo(c + (r - 10) * Math.sin(heading), c - (r - 10) * Math.cos(heading)); ctx.stroke();
  ctx.strokeStyle = "#ccd"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(c, c); ctx.lineTo(c - (r - 30) * Math.sin(heading), c + (r - 30) * Math.cos(heading)); ctx.stroke();
}

function attitudeText(att) {
  const h = ((90 - deg(att.yaw)) % 360 + 360) % 360;
  return `heading ${fmt(h, 1)}&deg; &middot; pitch ${fmt(deg(att.pitch), 1)}&deg; &middot; roll ${fmt(deg(att.roll), 1)}&deg;` +
    (att.source ? ` <span class="dim">(${att.source})</span>` : "");
}

// A foxglove.RawImage (mono8 / mono16) drawn on a canvas.
function drawImage(canvas, img) {
  const w = img.width, h = img.height;
  if (!(w > 0 && h > 0) || w * h > 4e7) return false;
  const bytes = b64bytes(img.data), step = img.step || (img.encoding === "mono8" ? w : 2 * w);
  canvas.width = w; canvas.height = h;
  const ctx = canvas.getContext("2d"), out = ctx.createImageData(w, h);
  for (let r = 0; r < h; r++) {
    for (let c = 0; c < w; c++) {
      const v = img.encoding === "mono8" ? bytes[r * step + c] : bytes[r * step + 2 * c + 1];
      const o = 4 * (r * w + c);
      out.data[o] = out.data[o + 1] = out.data[o + 2] = v || 0; out.data[o + 3] = 255;
    }
  }
  ctx.putImageData(out, 0, 0);
  return true;
}

// The live log, filterable.
class Log {
  constructor(box, filter) {
    this.box = box; this.filter = filter; this.entries = [];
    filter.addEventListener("input", () => this.render());
  }
  add(kind, text) {
    this.entries.push({ kind, text, at: new Date().toLocaleTimeString() });
    if (this.entries.length > 3000) this.entries.splice(0, 1000);
    const f = this.filter.value.toLowerCase();
    if (!f || text.toLowerCase().includes(f)) this.append(this.entries[this.entries.length - 1]);
  }
  append(e) {
    const stick = this.box.scrollTop + this.box.clientHeight >= this.box.scrollHeight - 4;
    const div = document.createElement("div");
    div.className = e.kind; div.textContent = `${e.at} ${e.text}`;
    this.box.appendChild(div);
    while (this.box.childNodes.length > 1500) this.box.removeChild(this.box.firstChild);
    if (stick) this.box.scrollTop = this.box.scrollHeight;
  }
  render() {
    this.box.textContent = "";
    const f = this.filter.value.toLowerCase();
    this.entries.filter((e) => !f || e.text.toLowerCase().includes(f)).slice(-1500).forEach((e) => this.append(e));
  }
  texts() { return this.entries.map((e) => e.text); }
}

// The command line: history (Up/Down) and completion (Tab) from the forms `help` lists.
class CommandLine {
  constructor(input, hint, send) {
    this.input = input; this.hint = hint; this.send = send;
    this.history = []; this.at = 0; this.forms = [];
    input.addEventListener("keydown", (e) => this.key(e));
    input.addEventListener("input", () => this.showHint());
  }
  setHelp(text) {
    this.forms = (text || "").split("\n").map((l) => l.trim()).filter((l) => /^[a-z]/.test(l) && !l.startsWith("Numbers"))
      .map((l) => l.split(/\s{2,}/)[0]);
  }
  matches() {
    const v = this.input.value.trimStart().toLowerCase();
    return v ? this.forms.filter((f) => f.toLowerCase().startsWith(v) || v.startsWith(f.split(" ")[0] + " ") && f.startsWith(v.split(" ")[0])) : [];
  }
  showHint() { this.hint.textContent = this.matches().slice(0, 6).join("  |  "); }
  key(e) {
    if (e.key === "Enter") {
      const line = this.input.value.trim();
      if (!line) return;
      this.history.push(line); this.at = this.history.length;
      this.input.value = ""; this.hint.textContent = "";
      this.send(line);
    } else if (e.key === "ArrowUp" || e.key === "ArrowDown") {
      e.preventDefault();
      this.at = Math.max(0, Math.min(this.history.length, this.at + (e.key === "ArrowUp" ? -1 : 1)));
      this.input.value = this.history[this.at] || "";
    } else if (e.key === "Tab") {
      e.preventDefault();
      const m = this.matches();
      if (!m.length) return;
      // The words the candidates share, up to the first placeholder (an upper-case word).
      const words = m.map((f) => f.split(" "));
      const common = [];
      for (let i = 0; words.every((w) => i < w.length && w[i] === words[0][i] && !/^[A-Z]/.test(w[i])); i++) common.push(words[0][i]);
      if (common.join(" ").length >= this.input.value.trim().length) this.input.value = common.join(" ") + (m.length === 1 || common.length ? " " : "");
      this.showHint();
    }
  }
}

// Encoder counts and speeds from the last frame's odometry.
function encoderHtml(odometry) {
  if (!odometry || !odometry.length) return null;
  const last = odometry[odometry.length - 1], first = odometry[0], dt = last.t - first.t;
  const speed = (k) => (dt > 0 ? (last[k] - first[k]) / dt : 0);
  return `left ${last.left_counts} counts (${fmt(speed("left_counts"), 0)}/s) &middot; right ${last.right_counts} counts (${fmt(speed("right_counts"), 0)}/s)`;
}

// Power meters: battery state of charge as a bar, every other number as a value.
function powerHtml(p) {
  const rows = [];
  for (const [k, v] of Object.entries(p)) {
    if (typeof v === "boolean" || typeof v === "string") rows.push(`${esc(k)}: <b>${esc(v)}</b>`);
    if (typeof v !== "number" || k === "t") continue;
    const fraction = /soc|state_of_charge|fraction/.test(k) ? Math.max(0, Math.min(1, v)) : null;
    const meter = fraction === null ? "" : `<span class="meter"><div style="width:${100 * fraction}%"></div></span>`;
    rows.push(`${esc(k.replace(/_/g, " "))}: ${meter}<b>${fraction === null ? fmt(v, 1) : fmt(100 * v, 0) + " %"}</b>`);
  }
  return rows.join("<br>");
}

function componentRows(states) {
  const names = Object.keys(states);
  if (!names.length) return '<tr><td class="dim">no state yet</td></tr>';
  return names.map((n) => {
    const s = states[n], bad = /Failure|Emergency/.test(s.state) ? "error" : "";
    return `<tr><td>${esc(n)}</td><td class="${bad}"><b>${esc(s.state)}</b></td><td class="dim">${esc(s.message || "")}</td></tr>`;
  }).join("");
}
