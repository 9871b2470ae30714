// Plots with uPlot: curves of several cases overlaid on one x axis, markers
// at each case's inversion, and a movable cursor line.
import uPlot from "uplot";

function dark() {
  return window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches;
}

const axisColours = () => (dark() ? { stroke: "#ddd", grid: "#444" } : { stroke: "#222", grid: "#e5e5e5" });

/** Line styles by a stage's direction: tightening solid, loosening dashed, holding or rotating dotted. */
export const STYLES = {
  tighten: { dash: [], width: 1.8 },
  loosen: { dash: [7, 4], width: 1.8 },
  still: { dash: [2, 3], width: 1.5 },
};

/** Draws an event's marker at (x, y): a filled circle for an inversion, a hollow diamond for a flip back. */
function eventMarker(ctx, px, py, kind, colour) {
  const r = 5 * devicePixelRatio;
  ctx.beginPath();
  if (kind === "flip_back") {
    ctx.moveTo(px, py - r * 1.3);
    ctx.lineTo(px + r * 1.3, py);
    ctx.lineTo(px, py + r * 1.3);
    ctx.lineTo(px - r * 1.3, py);
    ctx.closePath();
    ctx.lineWidth = 2 * devicePixelRatio;
    ctx.strokeStyle = colour;
    ctx.stroke();
  } else {
    ctx.arc(px, py, r, 0, 2 * Math.PI);
    ctx.fillStyle = colour;
    ctx.fill();
  }
}

/**
 * Overlaid curves. `curves`: [{label, colour, points: [[x, y]...], mark: x|null,
 * dash?, width?, direction?, dots?}] (dots: each point marked); `events`: [{x, y, kind: "inversion"|"flip_back", colour}],
 * markers on the curves. Returns {plot, setMarker(x)}: a solid vertical line at x (the case page's snapshot).
 */
export function overlay(el, { title, x, y, curves, width, events = [], guides = [] }) {
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
    series: [{ label: x }, ...curves.map((c) => ({ label: c.label, stroke: c.colour, width: c.width || 1.5, dash: c.dash && c.dash.length ? c.dash : undefined, spanGaps: true, points: { show: !!c.dots, size: 7, fill: c.colour } }))],
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
          // Measured inversions: black dashed lines.
          ctx.strokeStyle = dark() ? "#eee" : "#111";
          ctx.setLineDash([2, 4]);
          for (const g of guides) {
            const px = u.valToPos(g, "x", true);
            ctx.beginPath();
            ctx.moveTo(px, u.bbox.top);
            ctx.lineTo(px, u.bbox.top + u.bbox.height);
            ctx.stroke();
          }
          ctx.setLineDash([]);
          for (const e of events) {
            if (e.y === null || e.y === undefined || !Number.isFinite(e.y)) continue;
            eventMarker(ctx, u.valToPos(e.x, "x", true), u.valToPos(e.y, "y", true), e.kind, e.colour || "#000");
          }
          if (marker !== null) {
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
  el.dataset.directions = [...new Set(curves.map((c) => c.direction).filter(Boolean))].sort().join(",");
  el.dataset.events = events.map((e) => e.kind).join(",");
  el.dataset.guides = String(guides.length);
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
 * The hysteresis band: between the tightening inversion (lo) and the flip back
 * (hi) at each x of `band` [[x, lo, hi]...], shaded under the points (a strip
 * of a few pixels where a single x carries it).
 */
function hysteresisBand(band, fill) {
  return (u) => {
    if (!band.length) return;
    const ctx = u.ctx;
    const sorted = band.slice().sort((p, q) => p[0] - q[0]);
    const half = 6 * devicePixelRatio;
    ctx.save();
    ctx.fillStyle = fill;
    // Contiguous runs of x in the band: one polygon each (upper edge out, lower edge back).
    ctx.beginPath();
    if (sorted.length === 1) {
      const [bx, lo, hi] = sorted[0];
      const px = u.valToPos(bx, "x", true);
      const top = u.valToPos(Math.max(lo, hi), "y", true);
      const bottom = u.valToPos(Math.min(lo, hi), "y", true);
      ctx.rect(px - half, top, 2 * half, bottom - top);
    } else {
      sorted.forEach(([bx, , hi], i) => {
        const px = u.valToPos(bx, "x", true);
        const py = u.valToPos(hi, "y", true);
        if (i === 0) ctx.moveTo(px, py); else ctx.lineTo(px, py);
      });
      for (const [bx, lo] of sorted.slice().reverse()) ctx.lineTo(u.valToPos(bx, "x", true), u.valToPos(lo, "y", true));
      ctx.closePath();
    }
    ctx.fill();
    ctx.restore();
  };
}

/**
 * Points (x, y), one per case: `points` (filled) where F bar falls through the
 * event, `loaded` (hollow) where it does not; and a dashed reference line
 * [[x, y]...]. Either list may be empty. A certified sweep adds `errors`
 * [[x, y, e]...] (error bars y +- e) and `unconverged` [[x, y]...] (red rings).
 * A loading program that loosens adds `flips` [[x, y]...] (the flip back, the
 * second fold, hollow green on a dashed line) and `band` [[x, lo, hi]...] (the
 * hysteresis between the folds, shaded); `unsteady` [[x, y]...] rings in
 * orange the points whose case was not quasi-static. `measured` [[x, y, e]...]:
 * measured inversions, black with their error bars. `integer`: the x axis
 * counts (n), ticks at whole numbers only.
 */
export function scatter(el, { title, x, y, points, loaded, reference, errors = [], unconverged = [], flips = [], band = [], unsteady = [], measured = [], integer = false, width }) {
  const xs = [...new Set([...points, ...loaded, ...reference, ...flips, ...unsteady, ...measured].map((p) => p[0]))].sort((a, b) => a - b);
  const pick = (list) => xs.map((v) => { const p = list.find((q) => q[0] === v); return p ? p[1] : null; });
  const a = axisColours();
  const series = [{ label: x }, { label: flips.length ? "inversion (tightening fold)" : "inversion (full model)", stroke: "#0072b2", width: flips.length ? 1.5 : 0, spanGaps: true, points: { show: true, size: 9, fill: "#0072b2" } }];
  const data = [xs, pick(points)];
  if (loaded.length) {
    series.push({ label: "F̄ does not fall (see the note below)", stroke: "#0072b2", width: 0, points: { show: true, size: 9, width: 2, fill: "transparent" } });
    data.push(pick(loaded));
  }
  if (reference.length) {
    series.push({ label: "simplified model (Sec. 5)", stroke: "#d55e00", dash: [6, 4], width: 1.5, spanGaps: true, points: { show: false } });
    data.push(pick(reference));
  }
  if (flips.length) {
    series.push({ label: "flip back (loosening fold)", stroke: "#009e73", dash: [6, 3], width: 1.5, spanGaps: true, points: { show: true, size: 9, width: 2, fill: "transparent" } });
    data.push(pick(flips));
  }
  if (unsteady.length) {
    series.push({ label: "not quasi-static (see the note below)", stroke: "#e69f00", width: 0, points: { show: true, size: 21, width: 2, fill: "transparent" } });
    data.push(pick(unsteady));
  }
  if (measured.length) {
    const ink = dark() ? "#eee" : "#111";
    series.push({ label: "measured (± error)", stroke: ink, width: 0, points: { show: true, size: 9, fill: ink } });
    data.push(pick(measured));
  }
  if (unconverged.length) {
    series.push({ label: "unconverged (see the note below)", stroke: "#d00000", width: 0, points: { show: true, size: 17, width: 2, fill: "transparent" } });
    data.push(pick(unconverged));
  }
  // The y scale takes in the bars' ends.
  const ends = [...errors, ...measured].flatMap(([, v, e]) => [v - e, v + e]).concat(band.flatMap(([, lo, hi]) => [lo, hi]));
  const yScale = ends.length
    ? { range: (u, min, max) => uPlot.rangeNum(Math.min(min, ...ends), Math.max(max, ...ends), 0.1, true) }
    : {};
  el.innerHTML = "";
  el.dataset.points = String(points.length + loaded.length);
  el.dataset.loaded = String(loaded.length);
  el.dataset.errorbars = String(errors.length);
  el.dataset.unconverged = String(unconverged.length);
  el.dataset.flips = String(flips.length);
  el.dataset.band = String(band.length);
  el.dataset.unsteady = String(unsteady.length);
  el.dataset.measured = String(measured.length);
  const whole = integer ? { incrs: [1, 2, 5, 10, 20, 50, 100], values: (u, vals) => vals.map((v) => (Number.isInteger(v) ? String(v) : "")) } : {};
  return new uPlot({
    title,
    width: width || Math.min(720, el.clientWidth || 720),
    height: 300,
    scales: { x: { time: false, range: padded }, y: yScale },
    axes: [
      { label: x, stroke: a.stroke, grid: { stroke: a.grid }, ...whole },
      { label: y, stroke: a.stroke, grid: { stroke: a.grid } },
    ],
    series,
    hooks: { drawAxes: [hysteresisBand(band, "rgba(0, 158, 115, 0.18)"), errorBars(errors, "#0072b2"), errorBars(measured, dark() ? "#eee" : "#111")] },
  }, data, el);
}
