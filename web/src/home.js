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

/**
 * The CaseParams schema of the OpenAPI document: the parameters (name, type,
 * default, description, `x-group`) in the table's order (`x-order`), and the
 * groups with their titles in form order (`x-groups`).
 */
async function schema() {
  const doc = await get("/api/openapi.json");
  const s = doc.components.schemas.CaseParams;
  const order = s["x-order"] || [];
  const at = (name) => (order.includes(name) ? order.indexOf(name) : order.length);
  const params = Object.entries(s.properties).map(([name, p]) => ({ name, ...p }))
    .sort((a, b) => at(a.name) - at(b.name) || a.name.localeCompare(b.name));
  const groups = s["x-groups"] || [...new Set(params.map((p) => p["x-group"]))].map((name) => ({ name, title: name }));
  return { params, groups };
}

/** Parameters the form sets otherwise: a start shape is a file's worth of points; the program has its editor. */
const SKIP = new Set(["initial_shape", "loading"]);
/** The group the form folds away under "advanced". */
const ADVANCED = "solver";
/** The rod's constants a named material sets. */
const MATERIAL_FIELDS = ["youngs_modulus", "density", "poisson_ratio"];
/** The grid axis that is not a parameter: a named material sets all three (server/src/spec.rs, MATERIAL_AXIS). */
const MATERIAL_AXIS = "material";

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

/**
 * The first sentence of a description: the field's one-line help (the whole
 * text is a click away). A sentence ends at a full stop before a capital or
 * the end, not at an abbreviation ("eqs. 8-10", "e.g.").
 */
export const firstSentence = (text) => (text.match(/^.*?\.(?=\s+[A-Z(]|\s*$)/s) || [text])[0].trim();

/** A parameter's label: the paper's symbol and its name in words ("E · youngs modulus", "n"). */
function labelOf(p) {
  const words = p.name.replace(/_/g, " ");
  const sym = p["x-symbol"];
  return sym && sym !== p.name ? `${sym} · ${words}` : words;
}

/** One parameter's row: label (the full doc as its title), value, grid axis, a folded doc, its error. */
function field(p) {
  const k = kind(p);
  const def = p.default === undefined || p.default === null ? "" : Array.isArray(p.default) ? p.default.join(", ") : String(p.default);
  const doc = p.description || "";
  const input = k === "boolean" || k === "enum"
    ? `<select id="p-${p.name}" name="${p.name}"><option value="">default (${esc(def)})</option>${(p.enum || ["true", "false"]).map((v) => `<option>${esc(v)}</option>`).join("")}</select>`
    : `<input id="p-${p.name}" name="${p.name}" inputmode="${k === "integer" || k === "number" ? "decimal" : "text"}" placeholder="${esc(def || "default")}">`;
  const first = firstSentence(doc);
  const rest = doc.slice(first.length).trim();
  const unit = p["x-unit"] ? `<span class="unit">${esc(p["x-unit"])}</span>` : "";
  return `<div class="field" data-param="${p.name}">
    <label for="p-${p.name}" title="${esc(doc)}">${esc(labelOf(p))}</label><span class="value">${input}${unit}</span>
    <input id="g-${p.name}" class="grid" aria-label="${esc(p.name)} grid values" placeholder="grid: values or start:stop:step">
    ${rest ? `<details class="doc"><summary>${esc(first)}</summary>${esc(rest)}</details>` : `<span class="doc">${esc(first)}</span>`}
    <span class="field-error" data-for="${p.name}" role="status"></span></div>`;
}

/** The material picker: fills E, rho and nu from a named material (`GET /api/materials`); a grid over materials. */
function materialPicker(materials) {
  if (!materials.length) return "";
  return `<div class="field material" data-param="${MATERIAL_AXIS}">
    <label for="material" title="A named material sets youngs_modulus, density and poisson_ratio">material</label>
    <select id="material"><option value="">custom (the values below)</option>${materials.map((m) =>
      `<option value="${esc(m.name)}">${esc(m.name)}: E ${m.youngs_modulus.toExponential(2)} Pa, ρ ${m.density} kg/m³, ν ${m.poisson_ratio}</option>`).join("")}</select>
    <input id="g-${MATERIAL_AXIS}" class="grid" aria-label="material grid values" placeholder="grid: ${esc(materials.map((m) => m.name).slice(0, 3).join(", "))}">
    <span class="help" id="material-source">Pick one to fill E, ρ and ν, or grid over names.</span>
    <span class="field-error" data-for="${MATERIAL_AXIS}" role="status"></span></div>`;
}

/** The loading programs offered as starting points of the editor; null: the default one tightening. */
export const PROGRAMS = {
  tighten: { label: "tighten (default)", program: null },
  hysteresis: { label: "tighten then loosen", program: [{ pull: {} }, { release: {} }] },
  twist: { label: "rotate then pull", program: [{ rotate: { turns: 1, ends: "one" } }, { pull: {} }] },
  soft: { label: "soft device", program: [{ soft: { stiffness_bar: 100, to_l_k_bar: 190 } }] },
};

/** Each stage's fields: name, kind (number, or a list of words), required, placeholder. */
const STAGES = {
  pull: [{ name: "to_l_k_bar", hint: "to the stopping rules" }],
  release: [{ name: "to_l_k_bar", hint: "back to the start" }],
  hold: [{ name: "seconds", required: true, hint: "s" }],
  rotate: [{ name: "turns", required: true, hint: "turns" }, { name: "ends", words: ["one", "both"] }],
  soft: [{ name: "stiffness_bar", required: true, hint: "k (EI / h^3)" }, { name: "to_l_k_bar", hint: "l_k bar" }],
};
const STAGE_DOC = {
  pull: "tighten at pull_speed",
  release: "loosen at pull_speed",
  hold: "hold the clamps still",
  rotate: "turn the clamps about the pull axis",
  soft: "pull through springs (a soft device)",
};

/** The loading-program editor: a preset program, then stages to add, remove, reorder and edit. */
class ProgramEditor {
  constructor(root, onchange) {
    this.root = root;
    this.onchange = onchange;
    this.stages = null;
    root.innerHTML = `<div class="field program" data-param="loading">
      <label for="program-preset" title="The stages the clamps go through after the knot has relaxed (docs/API.md, Loading programs)">loading</label>
      <select id="program-preset">${Object.entries(PROGRAMS).map(([k, p]) => `<option value="${k}">${esc(p.label)}</option>`).join("")}<option value="custom" hidden>custom</option></select>
      <span></span>
      <span class="help">The loading program: stages run in order after the knot has relaxed. Empty targets take the stopping rules (a pull) or the start (a release).</span>
      <span class="field-error" data-for="loading" role="status"></span></div>
      <ol id="stages" class="stages" aria-label="loading program stages"></ol>
      <p class="stage-add"><select id="stage-kind" aria-label="stage to add">${Object.keys(STAGES).map((k) => `<option value="${k}">${k}: ${esc(STAGE_DOC[k])}</option>`).join("")}</select>
        <button type="button" id="stage-add">Add stage</button>
        <code id="loading-json" class="program-json"></code></p>`;
    $("#program-preset", root).onchange = (e) => this.preset(e.target.value);
    $("#stage-add", root).onclick = () => {
      const k = $("#stage-kind", root).value;
      this.set([...(this.stages || [{ pull: {} }]), { [k]: k === "rotate" ? { turns: 1, ends: "one" } : k === "hold" ? { seconds: 1 } : k === "soft" ? { stiffness_bar: 100 } : {} }], "custom");
    };
    this.preset("tighten");
  }

  preset(name) {
    const p = PROGRAMS[name];
    if (p) this.set(p.program && structuredClone(p.program), name);
  }

  /** The program to submit: null for the default one tightening. */
  program() {
    return this.stages;
  }

  set(stages, presetName) {
    this.stages = stages && stages.length ? stages : null;
    $("#program-preset", this.root).value = presetName;
    const list = $("#stages", this.root);
    const shown = this.stages || [{ pull: {} }];
    list.innerHTML = shown.map((stage, i) => {
      const [k, body] = Object.entries(stage)[0];
      const inputs = STAGES[k].map((f) => f.words
        ? `<label>${f.name} <select data-stage="${i}" data-key="${f.name}">${f.words.map((w) => `<option${body[f.name] === w ? " selected" : ""}>${w}</option>`).join("")}</select></label>`
        : `<label>${f.name} <input data-stage="${i}" data-key="${f.name}" inputmode="decimal" size="8" value="${body[f.name] ?? ""}" placeholder="${esc(f.hint)}"${f.required ? " required" : ""}></label>`).join(" ");
      const fixed = !this.stages;
      return `<li class="stage" data-kind="${k}"><strong>${k}</strong> <span class="hint">${esc(STAGE_DOC[k])}</span> ${inputs}
        ${fixed ? "" : `<button type="button" data-up="${i}" aria-label="move stage ${i + 1} up"${i === 0 ? " disabled" : ""}>↑</button>
        <button type="button" data-remove="${i}" aria-label="remove stage ${i + 1}">Remove</button>`}</li>`;
    }).join("");
    for (const e of list.querySelectorAll("[data-stage]")) {
      e.oninput = e.onchange = (ev) => {
        ev.stopPropagation();
        this.edit(Number(e.dataset.stage), e.dataset.key, e.value);
      };
    }
    for (const b of list.querySelectorAll("[data-remove]")) {
      b.onclick = () => this.set(this.stages.filter((_, i) => i !== Number(b.dataset.remove)), "custom");
    }
    for (const b of list.querySelectorAll("[data-up]")) {
      b.onclick = () => {
        const i = Number(b.dataset.up);
        const s = this.stages.slice();
        [s[i - 1], s[i]] = [s[i], s[i - 1]];
        this.set(s, "custom");
      };
    }
    this.show();
  }

  edit(i, key, text) {
    const stages = structuredClone(this.stages || [{ pull: {} }]);
    const body = Object.values(stages[i])[0];
    const t = text.trim();
    if (!t) delete body[key];
    else body[key] = STAGES[Object.keys(stages[i])[0]].find((f) => f.name === key).words ? t : Number(t);
    this.stages = stages;
    $("#program-preset", this.root).value = "custom";
    this.show();
  }

  show() {
    $("#loading-json", this.root).textContent = this.stages ? JSON.stringify(this.stages) : "the default: one pull to the stopping rules";
    this.onchange();
  }
}

async function form() {
  const [{ params: all, groups }, materials] = await Promise.all([schema(), get("/api/materials").catch(() => [])]);
  const params = all.filter((p) => !SKIP.has(p.name));
  const rows = (g) => params.filter((p) => p["x-group"] === g).map(field).join("");
  const grouped = groups.map((g) => {
    const extra = (g.name === "rod" ? materialPicker(materials) : "") + rows(g.name) +
      (g.name === "loading" ? `<div id="program"></div>` : "");
    const set = `<fieldset class="group" data-group="${esc(g.name)}"><legend>${esc(g.title)}</legend>${extra}</fieldset>`;
    return g.name === ADVANCED
      ? `<details class="advanced" id="advanced"><summary>${esc(g.title)}: numerical options, defaults that suit most cases</summary>${set}</details>`
      : set;
  });
  const orphans = params.filter((p) => !groups.some((g) => g.name === p["x-group"]));
  $("#params").innerHTML = grouped.join("") +
    (orphans.length ? `<fieldset class="group" data-group="other"><legend>Other</legend>${orphans.map(field).join("")}</fieldset>` : "");
  const f = $("#custom");
  const picker = $("#material");
  if (picker) {
    picker.onchange = () => {
      const m = materials.find((x) => x.name === picker.value);
      for (const name of MATERIAL_FIELDS) {
        const input = $(`#p-${name}`);
        if (input) input.value = m ? String(m[name]) : "";
      }
      $("#material-source").textContent = m ? m.source : "Pick one to fill E, ρ and ν, or grid over names.";
      f.dispatchEvent(new Event("input"));
    };
  }
  const axes = [...params.map((p) => p.name), ...(picker ? [MATERIAL_AXIS] : [])];
  const count = () => {
    let n = 1;
    let bad = false;
    for (const name of axes) {
      try {
        const a = axis($(`#g-${name}`).value);
        if (a) n *= a.length;
        setError(name, "");
      } catch (e) {
        setError(name, "grid: " + e.message);
        bad = true;
      }
    }
    $("#count").textContent = bad ? "fix the grid" : cases(n);
  };
  const program = new ProgramEditor($("#program"), count);
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
    }
    for (const name of axes) {
      const a = axis($(`#g-${name}`).value);
      if (a) grid[name] = a;
    }
    const loading = program.program();
    if (loading) base.loading = loading;
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
      const elsewhere = [];
      for (const fe of e.fields) {
        const m = fe.field.match(/^(?:base|grid)\.([a-z_]+)/);
        const target = m ? m[1] : fe.field;
        if (document.querySelector(`.field-error[data-for="${target}"]`)) setError(target, `${fe.field}: ${fe.reason}`);
        elsewhere.push(`${fe.field}: ${fe.reason}`);
      }
      // Beside the button too: every problem, whichever field it marks.
      setError("form", `${e.fields.length === 1 ? "1 problem" : `${e.fields.length} problems`}: ${elsewhere.join("; ")}`);
      const first = f.querySelector(".field .field-error:not(:empty)");
      if (first) {
        const details = first.closest("details.advanced");
        if (details) details.open = true;
        first.closest(".field")?.querySelector("input,select")?.focus();
      }
    }
  };
}

function setError(field, text) {
  const e = document.querySelector(`.field-error[data-for="${field}"]`);
  if (e) e.textContent = text;
}
