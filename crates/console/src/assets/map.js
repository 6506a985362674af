// The map: terrain in elevation colours (MRPTA's OCU), sensed ground, hazards, planned and
// driven paths, sensing wedges, the rover with its heading and proximity readings, goal,
// waypoints, keep-out zones and the mission planner's draft.
"use strict";

function b64bytes(text) {
  const raw = atob(text || "");
  const bytes = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
  return bytes;
}

function b64f32(text) {
  const bytes = b64bytes(text);
  const view = new DataView(bytes.buffer);
  const out = new Float32Array(bytes.length >> 2);
  for (let i = 0; i < out.length; i++) out[i] = view.getFloat32(4 * i, true);
  return out;
}

// Byte planes of little-endian f32 (every value's first byte, then every second...).
function b64f32planes(text) {
  const bytes = b64bytes(text), n = bytes.length >> 2, out = new Float32Array(n);
  const view = new DataView(new ArrayBuffer(4));
  for (let i = 0; i < n; i++) {
    for (let k = 0; k < 4; k++) view.setUint8(k, bytes[k * n + i]);
    out[i] = view.getFloat32(0, true);
  }
  return out;
}

// A world message's heights, in either encoding the log has used.
function worldHeights(terrain) {
  return terrain.heights_f32_planes !== undefined ? b64f32planes(terrain.heights_f32_planes) : b64f32(terrain.heights_f32le);
}

// Elevation colour ramp: low blue, green, yellow, high red-brown.
function ramp(f) {
  const stops = [[0, [40, 70, 160]], [0.3, [60, 150, 90]], [0.6, [220, 200, 80]], [1, [170, 80, 50]]];
  for (let i = 1; i < stops.length; i++) {
    if (f <= stops[i][0]) {
      const [a, ca] = stops[i - 1], [b, cb] = stops[i];
      const t = (f - a) / (b - a);
      return ca.map((c, k) => c + t * (cb[k] - c));
    }
  }
  return stops[stops.length - 1][1];
}

class RoverMap {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.world = null;
    this.terrain = null; // offscreen canvas, one pixel a cell
    this.fog = null; // offscreen canvas: dark where unsensed
    this.draws = 0;
    this.reset();
  }

  reset() {
    this.truth = [];
    this.estimates = [];
    this.plan = [];
    this.wedges = [];
    this.contacts = [];
    this.proximity = null;
    this.sensedCount = 0;
    if (this.world) this.makeFog();
  }

  setWorld(w) {
    const g = w.terrain.grid;
    const heights = (t) => t.heights_f32_planes || t.heights_f32le || "";
    const same = this.world && JSON.stringify(this.world.terrain.grid) === JSON.stringify(g) &&
      heights(this.world.terrain) === heights(w.terrain);
    this.world = w;
    if (!same) {
      this.heights = worldHeights(w.terrain);
      this.renderTerrain();
      this.makeFog();
    }
    this.fit();
  }

  renderTerrain() {
    const g = this.world.terrain.grid, h = this.heights, nodata = this.world.terrain.nodata;
    let lo = Infinity, hi = -Infinity;
    for (const v of h) if (Number.isFinite(v) && v !== nodata) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    const span = hi > lo ? hi - lo : 1;
    const c = document.createElement("canvas");
    c.width = g.cols; c.height = g.rows;
    const img = c.getContext("2d").createImageData(g.cols, g.rows);
    for (let r = 0; r < g.rows; r++) {
      for (let col = 0; col < g.cols; col++) {
        const i = r * g.cols + col, v = h[i];
        const o = 4 * ((g.rows - 1 - r) * g.cols + col); // row 0 is south: drawn at the bottom
        if (!Number.isFinite(v) || v === nodata) { img.data[o + 3] = 0; continue; }
        // Hill shade from the north-west.
        const e = h[r * g.cols + Math.min(col + 1, g.cols - 1)] - h[r * g.cols + Math.max(col - 1, 0)];
        const n = h[Math.min(r + 1, g.rows - 1) * g.cols + col] - h[Math.max(r - 1, 0) * g.cols + col];
        const shade = Math.max(0.45, Math.min(1.25, 1 + (n - e) / (4 * g.resolution)));
        const rgb = ramp((v - lo) / span);
        img.data[o] = rgb[0] * shade; img.data[o + 1] = rgb[1] * shade; img.data[o + 2] = rgb[2] * shade;
        img.data[o + 3] = 255;
      }
    }
    c.getContext("2d").putImageData(img, 0, 0);
    this.terrain = c;
    this.range = [lo, hi];
  }

  makeFog() {
    const g = this.world.terrain.grid;
    this.fogScale = Math.max(1, Math.round(0.1 / g.resolution)); // fog cells of about 10 cm
    const c = document.createElement("canvas");
    c.width = Math.ceil(g.cols / this.fogScale); c.height = Math.ceil(g.rows / this.fogScale);
    const ctx = c.getContext("2d");
    ctx.fillStyle = "rgba(0,0,0,0.55)";
    ctx.fillRect(0, 0, c.width, c.height);
    this.fog = c;
    this.sensed = new Uint8Array(c.width * c.height);
    this.sensedCount = 0;
  }

  // Marks the ground a frame's clouds covered, placed with the pose of the same cycle.
  addClouds(clouds, pose) {
    if (!this.fog || !clouds) return;
    const g = this.world.terrain.grid, ctx = this.fog.getContext("2d");
    const cell = g.resolution * this.fogScale, cy = Math.cos(pose.yaw), sy = Math.sin(pose.yaw);
    this.wedges = [];
    for (const cl of clouds) {
      this.wedges.push({ pose: { x: pose.x, y: pose.y, yaw: pose.yaw }, wedge: cl.wedge });
      const p = b64f32(cl.points);
      for (let i = 0; i + 2 < p.length; i += 3) {
        const x = pose.x + cy * p[i] - sy * p[i + 1], y = pose.y + sy * p[i] + cy * p[i + 1];
        const cx = Math.floor((x - g.origin_x) / cell), ry = Math.floor((y - g.origin_y) / cell);
        if (cx < 0 || ry < 0 || cx >= this.fog.width || ry >= this.fog.height) continue;
        const k = ry * this.fog.width + cx;
        if (!this.sensed[k]) { this.sensed[k] = 1; this.sensedCount++; ctx.clearRect(cx, this.fog.height - 1 - ry, 1, 1); }
      }
    }
  }

  isSensed(x, y) {
    const g = this.world.terrain.grid, cell = g.resolution * this.fogScale;
    const cx = Math.floor((x - g.origin_x) / cell), ry = Math.floor((y - g.origin_y) / cell);
    return cx >= 0 && ry >= 0 && cx < this.fog.width && ry < this.fog.height && this.sensed[ry * this.fog.width + cx] === 1;
  }

  fit() {
    const g = this.world.terrain.grid, w = g.cols * g.resolution, h = g.rows * g.resolution;
    const size = Math.min(this.canvas.width / w, this.canvas.height / h);
    this.scale = size; // pixels per metre
    this.ox = (this.canvas.width - w * size) / 2;
    this.oy = (this.canvas.height - h * size) / 2;
  }

  // World (m) to canvas pixels, and back.
  toCanvas(x, y) {
    const g = this.world.terrain.grid;
    return [this.ox + (x - g.origin_x) * this.scale, this.oy + (g.rows * g.resolution - (y - g.origin_y)) * this.scale];
  }
  toWorld(px, py) {
    const g = this.world.terrain.grid;
    return [g.origin_x + (px - this.ox) / this.scale, g.origin_y + g.rows * g.resolution - (py - this.oy) / this.scale];
  }
  // World point to CSS pixels from the canvas's top-left corner (for clicks).
  worldToClient(x, y) {
    const [px, py] = this.toCanvas(x, y), r = this.canvas.getBoundingClientRect();
    return [px * r.width / this.canvas.width, py * r.height / this.canvas.height];
  }
  clientToWorld(event) {
    const r = this.canvas.getBoundingClientRect();
    return this.toWorld((event.clientX - r.left) * this.canvas.width / r.width, (event.clientY - r.top) * this.canvas.height / r.height);
  }

  polyline(points, style, width, dash) {
    if (points.length < 2) return;
    const ctx = this.ctx;
    ctx.beginPath();
    points.forEach((p, i) => { const [x, y] = this.toCanvas(p.x, p.y); i ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
    ctx.strokeStyle = style; ctx.lineWidth = width; ctx.setLineDash(dash || []);
    ctx.stroke(); ctx.setLineDash([]);
  }

  marker(p, colour, label, radius) {
    const ctx = this.ctx, [x, y] = this.toCanvas(p.x, p.y);
    ctx.beginPath(); ctx.arc(x, y, radius || 6, 0, 2 * Math.PI);
    ctx.fillStyle = colour; ctx.fill(); ctx.strokeStyle = "#000"; ctx.lineWidth = 1; ctx.stroke();
    if (label) { ctx.fillStyle = "#fff"; ctx.font = "bold 11px sans-serif"; ctx.fillText(label, x + 8, y - 6); }
  }

  zone(points, fill, stroke, closed) {
    if (!points.length) return;
    const ctx = this.ctx;
    ctx.beginPath();
    points.forEach((p, i) => { const [x, y] = this.toCanvas(p.x, p.y); i ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
    if (closed) { ctx.closePath(); ctx.fillStyle = fill; ctx.fill(); }
    ctx.strokeStyle = stroke; ctx.lineWidth = 2; ctx.stroke();
  }

  drawRover(pose) {
    const ctx = this.ctx, [x, y] = this.toCanvas(pose.x, pose.y), s = Math.max(8, 0.5 * this.scale);
    ctx.save(); ctx.translate(x, y); ctx.rotate(-pose.yaw);
    ctx.fillStyle = "#fff"; ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
    ctx.beginPath(); ctx.moveTo(1.4 * s, 0); ctx.lineTo(-s, 0.8 * s); ctx.lineTo(-0.6 * s, 0); ctx.lineTo(-s, -0.8 * s); ctx.closePath();
    ctx.fill(); ctx.stroke();
    if (this.proximity) {
      // SR2's ten forward proximity sensors, index 0 leftmost, on an arc ahead of the rover.
      for (let i = 0; i < this.proximity.length; i++) {
        const a = (0.5 - i / (this.proximity.length - 1)) * 1.6;
        ctx.beginPath(); ctx.arc(2.2 * s * Math.cos(a), -2.2 * s * Math.sin(a), 3.5, 0, 2 * Math.PI);
        ctx.fillStyle = this.proximity[i] ? "#f33" : "rgba(120,255,120,0.7)"; ctx.fill();
      }
    }
    ctx.restore();
  }

  drawWedge(wd) {
    const ctx = this.ctx, [x, y] = this.toCanvas(wd.pose.x, wd.pose.y), w = wd.wedge;
    if (!w) return;
    const a0 = -(wd.pose.yaw + w.bearing) - w.half_angle, a1 = -(wd.pose.yaw + w.bearing) + w.half_angle;
    ctx.beginPath();
    ctx.arc(x, y, w.max_range * this.scale, a0, a1);
    ctx.arc(x, y, Math.max(0, w.min_range) * this.scale, a1, a0, true);
    ctx.closePath(); ctx.fillStyle = "rgba(120,200,255,0.12)"; ctx.fill();
    ctx.strokeStyle = "rgba(120,200,255,0.6)"; ctx.lineWidth = 1; ctx.stroke();
  }

  // Draws everything; `draft` is the mission planner's plan not yet sent.
  draw(draft) {
    const ctx = this.ctx;
    ctx.fillStyle = "#111"; ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    if (!this.world) {
      ctx.fillStyle = "#888"; ctx.font = "16px sans-serif"; ctx.fillText("waiting for the world...", 20, 30);
      return;
    }
    const g = this.world.terrain.grid, w = g.cols * g.resolution * this.scale, h = g.rows * g.resolution * this.scale;
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(this.terrain, this.ox, this.oy, w, h);
    ctx.drawImage(this.fog, this.ox, this.oy, w, h);
    // Rocks: hazards in red once sensed, faint until then.
    for (const rock of this.world.terrain.rocks || []) {
      const [x, y] = this.toCanvas(rock.x, rock.y);
      ctx.beginPath(); ctx.arc(x, y, Math.max(1.5, rock.diameter / 2 * this.scale), 0, 2 * Math.PI);
      ctx.strokeStyle = this.isSensed(rock.x, rock.y) ? "rgba(255,60,40,0.95)" : "rgba(0,0,0,0.25)";
      ctx.lineWidth = 1; ctx.stroke();
    }
    const goal = this.world.goal;
    for (const z of goal.keep_out || []) this.zone(z, "rgba(255,0,0,0.25)", "#f44", true);
    this.wedges.forEach((wd) => this.drawWedge(wd));
    this.polyline(this.plan, "#ffdd33", 2, [6, 4]);
    this.polyline(this.estimates, "rgba(120,200,255,0.9)", 1.5, [3, 3]);
    this.polyline(this.truth, "#ffffff", 2.5);
    for (const c of this.contacts) this.marker(c, "#f0f", "contact", 5);
    (goal.waypoints || []).forEach((p, i) => this.marker(p, "#39f", "W" + (i + 1)));
    this.marker(goal.position, "#3f6", "goal", 7);
    if (draft) {
      for (const z of draft.keep_out) this.zone(z, "rgba(255,140,0,0.25)", "#fa0", true);
      if (draft.zone.length) this.zone(draft.zone, "", "#fa0", false);
      draft.waypoints.forEach((p, i) => this.marker(p, "#9cf", "w" + (i + 1), 5));
      if (draft.goal) this.marker(draft.goal, "#9f9", "new goal", 6);
    }
    const rover = this.truth.length ? this.truth[this.truth.length - 1] : this.world.start;
    this.drawRover(rover);
    this.draws++;
  }
}
