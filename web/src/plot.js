// Plots with uPlot: curves of several cases overlaid on one x axis, markers
// at each case's inversion, and a movable cursor line.
import uPlot from "uplot";

function dark() {
  return window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches;
}

const axisColours = () => (dark() ? { stroke: "#ddd", grid: "#444" } : { stroke: "#222", grid: "#e5e5e5" });

/**
 * Overlaid curves. `curves`: [{label, colour, points: [[x, y]...], mark: x|null}].
 * Returns {plot, setMarker(x)}: a dashed vertical line at x (the case page's snapshot).
 */
export function overlay(el, { title, x, y, curves, width }) {
  const xs = [...new Set(curves.flatMap((c) => c.points.map((p) => p[0])))].sort((a, b) => a - b);
  const index = new Map(xs.map((v, i) => [v, i]));
  const data = [xs];
  for (const c of curves) {
    const ys = new Array(xs.length).fill(null);
    for (const [px, py] of c.points) ys[index.get(px)] = py;
    data.push(ys);
  }
  let marker = null;
  const a = axisColours();
  const opts = {
    title,
    width: width || Math.min(720, el.clientWidth || 720),
    height: 300,
    scales: { x: { time: false } },
    axes: [
      { label: x, stroke: a.stroke, grid: { stroke: a.grid } },
      { label: y, stroke: a.stroke, grid: { stroke: a.grid } },
    ],
    series: [{ label: x }, ...curves.map((c) => ({ label: c.label, stroke: c.colour, width: 1.5, spanGaps: true, points: { show: false } }))],
    hooks: {
      draw: [
        (u) => {
          const ctx = u.ctx;
          ctx.save();
          ctx.setLineDash([4, 4]);
          curves.forEach((c) => {
            if (c.mark === null || c.mark === undefined) return;
            const px = u.valToPos(c.mark, "x", true);
            ctx.strokeStyle = c.colour;
            ctx.beginPath();
            ctx.moveTo(px, u.bbox.top);
            ctx.lineTo(px, u.bbox.top + u.bbox.height);
            ctx.stroke();
          });
          if (marker !== null) {
            ctx.setLineDash([]);
            ctx.strokeStyle = dark() ? "#fff" : "#000";
            ctx.lineWidth = 2;
            const px = u.valToPos(marker, "x", true);
            ctx.beginPath();
            ctx.moveTo(px, u.bbox.top);
            ctx.lineTo(px, u.bbox.top + u.bbox.height);
            ctx.stroke();
          }
          ctx.restore();
        },
      ],
    },
  };
  el.innerHTML = "";
  el.dataset.series = String(curves.length);
  const plot = new uPlot(opts, data, el);
  return {
    plot,
    setMarker(x) {
      marker = x;
      plot.redraw(false);
    },
  };
}

/** An x range with room either side, so that the end points (and their bars) are not cut. */
function padded(u, min, max) {
  const pad = (max - min) * 0.04 || Math.abs(min) * 0.04 || 1;
  return [min - pad, max + pad];
}

/**
 * Error bars y +- e at x, drawn under uPlot's points: `bars` [[x, y, e]...].
 * (uPlot has none built in: a `drawAxes` hook, which runs after the grid and
 * before the series, draws them on the plot's canvas.)
 */
function errorBars(bars, colour) {
  return (u) => {
    const ctx = u.ctx;
    const cap = 4 * devicePixelRatio;
    ctx.save();
    ctx.strokeStyle = colour;
    ctx.lineWidth = 1.5 * devicePixelRatio;
    ctx.beginPath();
    for (const [x, y, e] of bars) {
      const px = u.valToPos(x, "x", true);
      const lo = u.valToPos(y - e, "y", true);
      const hi = u.valToPos(y + e, "y", true);
      ctx.moveTo(px, lo);
      ctx.lineTo(px, hi);
      ctx.moveTo(px - cap, lo);
      ctx.lineTo(px + cap, lo);
      ctx.moveTo(px - cap, hi);
      ctx.lineTo(px + cap, hi);
    }
    ctx.stroke();
    ctx.restore();
  };
}

/**
 * Points (x, y), one per case: `points` (filled) where F bar falls through the
 * event, `loaded` (hollow) where it does not; and a dashed reference line
 * [[x, y]...]. Either list may be empty. A certified sweep adds `errors`
 * [[x, y, e]...] (error bars y +- e) and `unconverged` [[x, y]...] (red rings).
 */
export function scatter(el, { title, x, y, points, loaded, reference, errors = [], unconverged = [], width }) {
  const xs = [...new Set([...points, ...loaded, ...reference].map((p) => p[0]))].sort((a, b) => a - b);
  const pick = (list) => xs.map((v) => { const p = list.find((q) => q[0] === v); return p ? p[1] : null; });
  const a = axisColours();
  const series = [{ label: x }, { label: "inversion (full model)", stroke: "#0072b2", width: 0, points: { show: true, size: 9, fill: "#0072b2" } }];
  const data = [xs, pick(points)];
  if (loaded.length) {
    series.push({ label: "F bar does not fall (see the note below)", stroke: "#0072b2", width: 0, points: { show: true, size: 9, width: 2, fill: "transparent" } });
    data.push(pick(loaded));
  }
  if (reference.length) {
    series.push({ label: "simplified model (Sec. 5)", stroke: "#d55e00", dash: [6, 4], width: 1.5, spanGaps: true, points: { show: false } });
    data.push(pick(reference));
  }
  if (unconverged.length) {
    series.push({ label: "unconverged (see the note below)", stroke: "#d00000", width: 0, points: { show: true, size: 17, width: 2, fill: "transparent" } });
    data.push(pick(unconverged));
  }
  // The y scale takes in the bars' ends.
  const ends = errors.flatMap(([, v, e]) => [v - e, v + e]);
  const yScale = ends.length
    ? { range: (u, min, max) => uPlot.rangeNum(Math.min(min, ...ends), Math.max(max, ...ends), 0.1, true) }
    : {};
  el.innerHTML = "";
  el.dataset.points = String(points.length + loaded.length);
  el.dataset.loaded = String(loaded.length);
  el.dataset.errorbars = String(errors.length);
  el.dataset.unconverged = String(unconverged.length);
  return new uPlot({
    title,
    width: width || Math.min(720, el.clientWidth || 720),
    height: 300,
    scales: { x: { time: false, range: padded }, y: yScale },
    axes: [
      { label: x, stroke: a.stroke, grid: { stroke: a.grid } },
      { label: y, stroke: a.stroke, grid: { stroke: a.grid } },
    ],
    series,
    hooks: { drawAxes: [errorBars(errors, "#0072b2")] },
  }, data, el);
}
