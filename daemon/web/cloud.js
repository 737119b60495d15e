// The 3D view: points in the left camera's frame (mm), drawn with a perspective orbit camera on a 2D
// canvas (a few hundred points need no WebGL). Drag rotates about the points' centre, the wheel zooms.
import { turbo, drawScale } from "./colormap.js";

export class CloudView {
  constructor(canvas) {
    this.canvas = canvas;
    this.yaw = 0;
    this.pitch = 0;
    this.zoom = 1;
    this.colourBy = "depth";
    this.points = [];  // {xyz: [x, y, z], sigma, scene}
    this.board = null; // four corners [x, y, z] of the fitted board, or null
    this.drawn = 0;    // points drawn by the last frame (read by the browser tests)
    let drag = null;
    canvas.addEventListener("pointerdown", (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      this.yaw += (e.clientX - drag.x) * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + (e.clientY - drag.y) * 0.01));
      drag = { x: e.clientX, y: e.clientY };
      this.draw();
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.zoom = Math.max(0.2, Math.min(20, this.zoom * Math.exp(-e.deltaY * 0.001)));
      this.draw();
    }, { passive: false });
  }

  reset() { this.yaw = 0; this.pitch = 0; this.zoom = 1; this.draw(); }

  set(points, board) {
    this.points = points;
    this.board = board;
    this.draw();
  }

  draw() {
    const c = this.canvas.getContext("2d");
    const { width: w, height: h } = this.canvas;
    c.clearRect(0, 0, w, h);
    this.drawn = 0;
    const pts = this.points;
    if (!pts.length) {
      c.fillStyle = "#8a939c";
      c.font = "13px system-ui, sans-serif";
      c.textAlign = "center";
      c.fillText("no valid 3D points in the latest result", w / 2, h / 2);
      return;
    }
    // Orbit about the centroid; the camera looks along +Z of the left camera's frame (image-like view
    // at yaw = pitch = 0: x right, y down).
    const centre = [0, 0, 0];
    for (const p of pts) for (let k = 0; k < 3; ++k) centre[k] += p.xyz[k] / pts.length;
    let radius = 1e-3;
    for (const p of pts) radius = Math.max(radius, Math.hypot(p.xyz[0] - centre[0], p.xyz[1] - centre[1], p.xyz[2] - centre[2]));
    const dist = (3 * radius) / this.zoom;
    const cy = Math.cos(this.yaw), sy = Math.sin(this.yaw), cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    const f = Math.min(w, h) * 0.9;
    const project = (q) => {
      const x = q[0] - centre[0], y = q[1] - centre[1], z = q[2] - centre[2];
      const x1 = cy * x + sy * z, z1 = -sy * x + cy * z;
      const y2 = cp * y - sp * z1, z2 = sp * y + cp * z1 + dist;
      if (z2 <= 1e-6) return null;
      return [w / 2 + (f * x1) / z2 / 3, h / 2 + (f * y2) / z2 / 3, z2];
    };
    const values = pts.map((p) => (this.colourBy === "sigma" ? p.sigma : p.xyz[2]));
    const finite = values.filter(Number.isFinite);
    const lo = finite.length ? Math.min(...finite) : 0, hi = finite.length ? Math.max(...finite) : 1;
    if (this.board) {
      const q = this.board.map(project);
      if (q.every(Boolean)) {
        c.fillStyle = "rgba(88,166,255,0.12)";
        c.strokeStyle = "rgba(88,166,255,0.7)";
        c.beginPath();
        q.forEach((p, i) => (i ? c.lineTo(p[0], p[1]) : c.moveTo(p[0], p[1])));
        c.closePath();
        c.fill();
        c.stroke();
      }
    }
    const order = pts.map((p, i) => ({ i, q: project(p.xyz) })).filter((o) => o.q).sort((a, b) => b.q[2] - a.q[2]);
    for (const { i, q } of order) {
      const v = values[i];
      c.fillStyle = Number.isFinite(v) ? turbo(hi > lo ? (v - lo) / (hi - lo) : 0.5) : "#8a939c";
      const r = pts[i].scene ? 1.6 : 2.6;
      c.beginPath();
      c.arc(q[0], q[1], r, 0, 2 * Math.PI);
      c.fill();
      ++this.drawn;
    }
    drawScale(c, 10, h - 30, 220, 8, lo, hi, this.colourBy === "sigma" ? "mm (depth sigma)" : "mm (depth)");
  }
}
