// A small live line plot of the status latencies (one sample per status poll).
export class LatencyPlot {
  constructor(canvas, seconds) {
    this.canvas = canvas;
    this.seconds = seconds;
    this.samples = [];  // {t, values: [..]}
    this.colours = ["#f0883e", "#58a6ff", "#3fb950"];
  }

  add(t, values) {
    this.samples.push({ t, values });
    while (this.samples.length && this.samples[0].t < t - this.seconds) this.samples.shift();
    this.draw();
  }

  draw() {
    const c = this.canvas.getContext("2d");
    const { width: w, height: h } = this.canvas;
    c.clearRect(0, 0, w, h);
    if (this.samples.length < 2) return;
    let top = 0.1;
    for (const s of this.samples) for (const v of s.values) if (Number.isFinite(v)) top = Math.max(top, v);
    top *= 1.15;
    const t1 = this.samples[this.samples.length - 1].t;
    const x = (t) => w - ((t1 - t) / this.seconds) * w;
    const y = (v) => h - 14 - (v / top) * (h - 20);
    c.strokeStyle = "#2d333b";
    c.fillStyle = "#8a939c";
    c.font = "10px system-ui, sans-serif";
    for (const f of [0.5, 1]) {
      c.beginPath();
      c.moveTo(0, y(top * f / 1.15));
      c.lineTo(w, y(top * f / 1.15));
      c.stroke();
      c.fillText(`${(top * f / 1.15).toFixed(2)} ms`, 2, y(top * f / 1.15) - 2);
    }
    this.colours.forEach((colour, k) => {
      c.strokeStyle = colour;
      c.beginPath();
      let started = false;
      for (const s of this.samples) {
        const v = s.values[k];
        if (!Number.isFinite(v)) { started = false; continue; }
        if (started) c.lineTo(x(s.t), y(v)); else c.moveTo(x(s.t), y(v));
        started = true;
      }
      c.stroke();
    });
  }
}
