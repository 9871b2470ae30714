// The front page: the sweeps (a page at a time, with controls) and the
// submission form generated from the API's CaseParams schema.
import { api, get, limits, ApiError } from "./api.js";
import { esc, fmt, duration, when, notice, $ } from "./util.js";

const PAGE = 20;
const FINISHED = new Set(["done", "cancelled"]);
let offset = 0;
let timer = null;
/** The service's limits (`GET /api/limits`), once read. */
let served = null;

export async function home(main) {
  main.innerHTML = `
    <section aria-labelledby="sweeps-h">
      <h1 id="sweeps-h">Sweeps</h1>
      <div class="table-wrap"><table class="sweeps">
        <thead><tr><th scope="col">Sweep</th><th scope="col">Status</th><th scope="col">Progress</th>
          <th scope="col">Cases</th><th scope="col">ETA</th><th scope="col">Created</th><th scope="col">Actions</th></tr></thead>
        <tbody id="sweeps"><tr><td colspan="7">Loading…</td></tr></tbody>
      </table></div>
      <div class="pager"><button id="prev" type="button">Newer</button> <span id="page"></span>
        <button id="next" type="button">Older</button></div>
    </section>
    <section aria-labelledby="submit-h">
      <h1 id="submit-h">Submit a sweep</h1>
      <p class="certify"><input id="certify" type="checkbox"> <label for="certify">Certify every point: also run a refined
        twin (time step halved) of each case and show the inversion's numerical uncertainty (about 3x the cost)</label></p>
      <h2>The paper's phase diagrams</h2>
      <div id="presets" class="presets">Loading presets…</div>
      <h2>Your own</h2>
      <form id="custom" novalidate>
        <p class="hint">Every parameter in SI units; leave a value empty for its default. A grid axis takes a list
          (<code>0.1, 0.2, 0.3</code>) or <code>start:stop:step</code> (<code>0.1:0.5:0.1</code>); the sweep is every
          combination.</p>
        <div class="field"><label for="sweep-name">Name</label><input id="sweep-name" name="name" placeholder="optional">
          <span class="field-error" data-for="name" role="status"></span></div>
        <div id="params" class="params">Loading the parameter schema…</div>
        <p><strong id="count">1 case</strong> <button type="submit">Submit</button>
          <span class="field-error" data-for="form" role="status"></span></p>
      </form>
    </section>`;
  $("#prev").onclick = () => { offset = Math.max(0, offset - PAGE); refresh(); };
  $("#next").onclick = () => { offset += PAGE; refresh(); };
  $("#certify").onchange = () => {
    presetCounts();
    $("#custom").dispatchEvent(new Event("input"));
  };
  served = await limits().catch(() => null);
  await Promise.all([presets(), form(), refresh()]);
  clearInterval(timer);
  timer = setInterval(() => { if (location.hash === "" || location.hash === "#/") refresh(); else clearInterval(timer); }, 3000);
}

async function refresh() {
  try {
    const head = await api("GET", `/api/sweeps?limit=1`);
    const total = head.total;
    // Newest first: the API lists oldest first.
    const start = Math.max(0, total - offset - PAGE);
    const count = Math.min(PAGE, total - offset);
    const sweeps = count > 0 ? (await get(`/api/sweeps?limit=${count}&offset=${start}`)).reverse() : [];
    const details = await Promise.all(sweeps.map((s) => (FINISHED.has(s.status) ? null : get(`/api/sweeps/${s.id}`).catch(() => null))));
    $("#sweeps").innerHTML = sweeps.length === 0 ? `<tr><td colspan="7">No sweeps yet: submit one below.</td></tr>` :
      sweeps.map((s, i) => row(s, details[i])).join("");
    $("#page").textContent = total ? `${offset + 1}–${offset + sweeps.length} of ${total}` : "";
    $("#prev").disabled = offset === 0;
    $("#next").disabled = offset + PAGE >= total;
    for (const b of document.querySelectorAll("#sweeps button[data-action]")) {
      b.onclick = () => control(b.dataset.id, b.dataset.action);
    }
  } catch (e) {
    notice(e instanceof ApiError ? e.message : "Cannot reach the server: " + e);
  }
}

function finishedFraction(s) {
  const left = (s.counts.queued || 0) + (s.counts.running || 0);
  return s.total ? (s.total - left) / s.total : 1;
}

function row(s, d) {
  const progress = d ? d.progress : finishedFraction(s);
  const counts = Object.entries(s.counts).map(([k, v]) => `${esc(k)} ${v}`).join(", ");
  const actions = s.state === "cancelled" ? "" :
    (s.state === "paused" ? `<button type="button" data-id="${s.id}" data-action="resume">Resume</button>` :
      FINISHED.has(s.status) ? "" : `<button type="button" data-id="${s.id}" data-action="pause">Pause</button>`) +
    (FINISHED.has(s.status) ? "" : ` <button type="button" data-id="${s.id}" data-action="cancel">Cancel</button>`);
  return `<tr>
    <td><a href="#/sweeps/${s.id}">#${s.id} ${esc(s.name || s.preset || "custom")}</a></td>
    <td><span class="status s-${esc(s.status)}">${esc(s.status)}</span></td>
    <td><progress max="1" value="${progress}" aria-label="sweep ${s.id} progress">${fmt(100 * progress, 0)} %</progress></td>
    <td>${s.total}: ${counts}</td>
    <td>${d ? duration(d.eta_seconds) : "–"}</td>
    <td>${when(s.created_at)}</td>
    <td>${actions}</td></tr>`;
}

async function control(id, action) {
  try {
    await api("POST", `/api/sweeps/${id}/${action}`, {});
    notice("");
  } catch (e) {
    notice(e.message);
  }
  refresh();
}

/** The "certify" checkbox is ticked: every case gets its refined twin. */
const certify = () => $("#certify")?.checked === true;

/** "N cases", or with certify "2N cases: N points and their refined twins"; beyond the service's limit, says so. */
function cases(n) {
  const plural = (k, word) => `${k} ${word}${k === 1 ? "" : "s"}`;
  const total = certify() ? 2 * n : n;
  const text = certify() ? `${plural(total, "case")}: ${plural(n, "point")} and ${n === 1 ? "its" : "their"} refined twin${n === 1 ? "" : "s"}` : plural(n, "case");
  return served && total > served.max_cases ? `${text}, over the limit of ${served.max_cases} cases per sweep` : text;
}

function presetCounts() {
  for (const s of document.querySelectorAll("#presets [data-cases]")) s.textContent = cases(Number(s.dataset.cases));
}

async function presets() {
  const list = await get("/api/presets");
  $("#presets").innerHTML = list.map((p) =>
    `<button type="button" data-preset="${esc(p.name)}">${esc(p.name)}</button> <span>${esc(p.description)} (<span data-cases="${p.cases}"></span>)</span>`
  ).join("<br>");
  presetCounts();
  for (const b of document.querySelectorAll("#presets button")) {
    b.onclick = async () => {
      try {
        const body = { preset: b.dataset.preset };
        if (certify()) body.certify = true;
        const r = await api("POST", "/api/sweeps", body);
        location.hash = `#/sweeps/${r.body.id}`;
      } catch (e) {
        notice(e.message);
      }
    };
  }
}

/** The CaseParams schema of the OpenAPI document: name, type, default, description. */
async function schema() {
  const doc = await get("/api/openapi.json");
  const s = doc.components.schemas.CaseParams;
  return Object.entries(s.properties).map(([name, p]) => ({ name, ...p }));
}

const SKIP = new Set(["initial_shape"]);
/** The parameters a study varies first, in the paper's order; the rest follow alphabetically. */
const FIRST = ["n", "h", "mu", "length", "nodes", "friction_law", "rolling", "gravity"];
const rank = (name) => (FIRST.includes(name) ? FIRST.indexOf(name) : FIRST.length);

function kind(p) {
  const t = Array.isArray(p.type) ? p.type.filter((x) => x !== "null")[0] : p.type;
  if (p.enum) return "enum";
  return t || "string";
}

/** Parses one grid axis: a list or start:stop:step (inclusive). */
export function axis(text) {
  const t = text.trim();
  if (!t) return null;
  const range = t.match(/^(-?[\d.eE+-]+)\s*:\s*(-?[\d.eE+-]+)\s*:\s*(-?[\d.eE+-]+)$/);
  if (range) {
    const [a, b, step] = range.slice(1).map(Number);
    if (!(step > 0) || !(b >= a)) throw new Error("start:stop:step needs step > 0 and stop >= start");
    const n = Math.floor((b - a) / step + 1e-9) + 1;
    if (n > 10000) throw new Error("too many values");
    return Array.from({ length: n }, (_, i) => Number((a + i * step).toPrecision(12)));
  }
  return t.split(/[,\s]+/).filter(Boolean).map((v) => {
    if (v === "true" || v === "false") return v === "true";
    const x = Number(v);
    if (Number.isNaN(x)) return v;
    return x;
  });
}

function value(p, text) {
  const t = text.trim();
  if (!t) return undefined;
  switch (kind(p)) {
    case "integer":
    case "number": return Number(t);
    case "boolean": return t === "true";
    case "array": return t.split(/[,\s]+/).filter(Boolean).map(Number);
    default: return t;
  }
}

async function form() {
  const params = (await schema())
    .filter((p) => !SKIP.has(p.name))
    .sort((a, b) => rank(a.name) - rank(b.name) || a.name.localeCompare(b.name));
  $("#params").innerHTML = params.map((p) => {
    const k = kind(p);
    const def = p.default === undefined || p.default === null ? "" : Array.isArray(p.default) ? p.default.join(", ") : String(p.default);
    const input = k === "boolean" || k === "enum"
      ? `<select id="p-${p.name}" name="${p.name}"><option value="">default (${esc(def)})</option>${(p.enum || ["true", "false"]).map((v) => `<option>${esc(v)}</option>`).join("")}</select>`
      : `<input id="p-${p.name}" name="${p.name}" inputmode="${k === "integer" || k === "number" ? "decimal" : "text"}" placeholder="${esc(def || "default")}">`;
    return `<div class="field">
      <label for="p-${p.name}">${esc(p.name)}</label>${input}
      <input id="g-${p.name}" class="grid" aria-label="${esc(p.name)} grid values" placeholder="grid: values or start:stop:step">
      <span class="help">${esc(p.description || "")}</span>
      <span class="field-error" data-for="${p.name}" role="status"></span></div>`;
  }).join("");
  const f = $("#custom");
  const count = () => {
    let n = 1;
    let bad = false;
    for (const p of params) {
      try {
        const a = axis($(`#g-${p.name}`).value);
        if (a) n *= a.length;
        setError(p.name, "");
      } catch (e) {
        setError(p.name, "grid: " + e.message);
        bad = true;
      }
    }
    $("#count").textContent = bad ? "fix the grid" : cases(n);
  };
  f.oninput = count;
  count();
  f.onsubmit = async (ev) => {
    ev.preventDefault();
    for (const e of f.querySelectorAll(".field-error")) e.textContent = "";
    const base = {};
    const grid = {};
    for (const p of params) {
      const v = value(p, $(`#p-${p.name}`).value);
      if (v !== undefined) base[p.name] = v;
      const a = axis($(`#g-${p.name}`).value);
      if (a) grid[p.name] = a;
    }
    const body = { base, grid };
    if (certify()) body.certify = true;
    const name = $("#sweep-name").value.trim();
    if (name) body.name = name;
    try {
      const r = await api("POST", "/api/sweeps", body);
      location.hash = `#/sweeps/${r.body.id}`;
    } catch (e) {
      if (!(e instanceof ApiError) || e.fields.length === 0) {
        setError("form", e.message);
        return;
      }
      for (const fe of e.fields) {
        const m = fe.field.match(/^(?:base|grid)\.([a-z_]+)/);
        const target = m ? m[1] : fe.field;
        setError(document.querySelector(`.field-error[data-for="${target}"]`) ? target : "form", `${fe.field}: ${fe.reason}`);
      }
      const first = f.querySelector(".field-error:not(:empty)");
      if (first) first.closest(".field")?.querySelector("input,select")?.focus();
    }
  };
}

function setError(field, text) {
  const e = document.querySelector(`.field-error[data-for="${field}"]`);
  if (e) e.textContent = text;
}
