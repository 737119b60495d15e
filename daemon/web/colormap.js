// Turbo colour map (Google's polynomial approximation, Mikhailov 2019): t in [0, 1] -> "rgb(...)".
export function turbo(t) {
  const x = Math.min(1, Math.max(0, t));
  const r = 34.61 + x * (1172.33 - x * (10793.56 - x * (33300.12 - x * (38394.49 - x * 14825.05))));
  const g = 23.31 + x * (557.33 + x * (1225.33 - x * (3574.96 - x * (1073.77 + x * 707.56))));
  const b = 27.2 + x * (3211.1 - x * (15327.97 - x * (27814.0 - x * (22569.18 - x * 6838.66))));
  const c = (v) => Math.round(Math.min(255, Math.max(0, v)));
  return `rgb(${c(r)},${c(g)},${c(b)})`;
}

// A colour bar from lo to hi (unit given) drawn into a canvas 2D context at (x, y).
export function drawScale(ctx, x, y, w, h, lo, hi, unit) {
  for (let i = 0; i < w; ++i) {
    ctx.fillStyle = turbo(i / (w - 1));
    ctx.fillRect(x + i, y, 1, h);
  }
  ctx.fillStyle = "#e6e6e6";
  ctx.font = "11px system-ui, sans-serif";
  ctx.textBaseline = "top";
  ctx.textAlign = "left";
  ctx.fillText(lo.toFixed(2), x, y + h + 2);
  ctx.textAlign = "right";
  ctx.fillText(`${hi.toFixed(2)} ${unit}`, x + w, y + h + 2);
}
