// Small DOM helpers.
export const esc = (s) =>
  String(s ?? "").replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);

export const $ = (sel, root = document) => root.querySelector(sel);

export function fmt(x, digits = 1) {
  if (x === null || x === undefined || Number.isNaN(x)) return "–";
  return typeof x === "number" ? x.toFixed(digits) : String(x);
}

export function duration(s) {
  if (s === null || s === undefined) return "–";
  if (s < 90) return `${Math.round(s)} s`;
  if (s < 5400) return `${Math.round(s / 60)} min`;
  return `${(s / 3600).toFixed(1)} h`;
}

export function when(ms) {
  return ms ? new Date(ms).toLocaleString() : "–";
}

export function notice(text) {
  const n = $("#notice");
  n.textContent = text || "";
  n.hidden = !text;
}

/** Distinct colours for overlaid curves (colour-blind friendly order). */
export const PALETTE = ["#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#7f7f7f", "#f0e442", "#000000"];
export const colour = (i) => PALETTE[i % PALETTE.length];

export function download(name, text, type = "text/plain") {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([text], { type }));
  a.download = name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

/** The paper's symbols of the measured quantities. */
export const LK = "l̄_k";
export const FB = "F̄";
export const HB = "H̄";

/** A parameter's symbol (`x-symbol` of `props`, the CaseParams schema's properties), else its name. */
export const symbol = (name, props) => (props && props[name] && props[name]["x-symbol"]) || name;

/** An axis label: the symbol and its unit, h in mm as the paper's figures ("h (mm)", "μ", "L (m)"). */
export function axisLabel(name, props) {
  if (name === "h") return "h (mm)";
  const unit = props && props[name] && props[name]["x-unit"];
  return unit ? `${symbol(name, props)} (${unit})` : symbol(name, props);
}

/** A value on an axis: h in mm, the rest as they are. */
export const axisValue = (name, v) => (name === "h" ? Number(v) * 1e3 : Number(v));

/**
 * A parameter's value as legends and tables show it: symbol, value and unit,
 * h in mm ("h = 1.6 mm", "μ = 0.1", "E = 1.8e+6 Pa"); a null value is its
 * default.
 */
export function param(name, v, props) {
  if (v === null || v === undefined) return `${symbol(name, props)}: default`;
  if (name === "h" && typeof v === "number") return `h = ${Number((v * 1e3).toPrecision(6))} mm`;
  const unit = typeof v === "number" && props && props[name] && props[name]["x-unit"];
  return `${symbol(name, props)} = ${v}${unit ? ` ${unit}` : ""}`;
}
