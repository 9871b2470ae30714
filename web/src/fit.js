// Fits: a parameter (μ by default) found from measured inversions over queued
// cases (POST /api/fits), and one fit's search, value and interval.
import { api, get, paramInfo, ApiError } from "./api.js";
import { esc, fmt, notice, colour, $, LK, param, symbol, axisLabel } from "./util.js";
import { overlay } from "./plot.js";

const EXAMPLE = "n,h,l_k_bar,error\n3,3.4e-3,129.3,1.0\n4,1.6e-3,210.0,1.0\n";

/** The fits of this server and the form that starts one. */
export async function fitsPage(main) {
  main.innerHTML = `
    <p><a href="#/">← all sweeps</a></p>
    <h1>Fit a parameter to measured inversions</h1>
    <p class="hint">Give measured inversions (each its case parameters, ${LK} and its error); the server finds the value of the
      parameter that reproduces them by bracketing and regula falsi over queued cases (cached like any other), with an
      interval from the errors and, when certified, each case's numerical uncertainty.</p>
    <form id="fit-form" novalidate>
      <div class="field"><label for="fit-parameter">Parameter</label><select id="fit-parameter"></select>
        <span class="field-error" data-for="parameter" role="status"></span></div>
      <div class="field"><label for="fit-low">Range</label><span class="value"><input id="fit-low" value="0.05" inputmode="decimal" aria-label="low end">
        to <input id="fit-high" value="0.8" inputmode="decimal" aria-label="high end"><span class="unit" id="fit-unit"></span></span>
        <span class="field-error" data-for="range" role="status"></span></div>
      <div class="field"><label for="fit-points">Measured points (CSV)</label>
        <textarea id="fit-points" rows="5" spellcheck="false">${esc(EXAMPLE)}</textarea>
        <span class="field-error" data-for="points" role="status"></span></div>
      <div class="field"><label for="fit-base">Base parameters (JSON)</label><input id="fit-base" value="{}" spellcheck="false">
        <span class="field-error" data-for="base" role="status"></span></div>
      <p><input id="fit-certify" type="checkbox"> <label for="fit-certify">Certify every case (about 3x the cost)</label></p>
      <p><button type="submit">Start the fit</button> <span class="field-error" data-for="form" role="status"></span></p>
    </form>
    <h2>Fits on this server</h2>
    <div class="table-wrap"><table><thead><tr><th scope="col">Fit</th><th scope="col">Status</th><th scope="col">Value</th>
      <th scope="col">Interval</th><th scope="col">Evaluations</th></tr></thead><tbody id="fits"></tbody></table></div>`;
  const props = await paramInfo();
  const numeric = Object.entries(props).filter(([, p]) => p.type === "number" || (Array.isArray(p.type) && p.type.includes("number")));
  $("#fit-parameter").innerHTML = numeric.map(([name]) => `<option value="${esc(name)}"${name === "mu" ? " selected" : ""}>${esc(symbol(name, props))} · ${esc(name.replace(/_/g, " "))}</option>`).join("");
  const unit = () => { $("#fit-unit").textContent = props[$("#fit-parameter").value]?.["x-unit"] || ""; };
  $("#fit-parameter").onchange = unit;
  unit();
  const fits = await get("/api/fits");
  $("#fits").innerHTML = fits.length ? fits.slice().reverse().map((f) => `<tr><td><a href="#/fits/${f.id}">fit ${f.id}${f.name ? ` ${esc(f.name)}` : ""}</a></td>
    <td><span class="status s-${esc(f.status)}">${esc(f.status)}</span></td><td>${f.value === null ? "–" : esc(param(f.parameter, Number(f.value.toPrecision(4)), props))}</td>
    <td>${f.interval ? `[${fmt(f.interval[0], 4)}, ${fmt(f.interval[1], 4)}]` : "–"}</td><td>${f.evaluations.length}</td></tr>`).join("")
    : `<tr><td colspan="5">No fits yet.</td></tr>`;
  $("#fit-form").onsubmit = async (ev) => {
    ev.preventDefault();
    for (const e of document.querySelectorAll(".field-error")) e.textContent = "";
    const body = { parameter: $("#fit-parameter").value, range: [Number($("#fit-low").value), Number($("#fit-high").value)] };
    try {
      body.points = readCsv($("#fit-points").value);
      body.base = JSON.parse($("#fit-base").value || "{}");
    } catch (e) {
      setError("form", e.message);
      return;
    }
    if ($("#fit-certify").checked) body.certify = true;
    try {
      const r = await api("POST", "/api/fits", body);
      location.hash = `#/fits/${r.body.id}`;
    } catch (e) {
      const fields = e instanceof ApiError ? e.fields : [];
      for (const f of fields) setError(f.field.split(/[.[]/)[0], `${f.field}: ${f.reason}`);
      setError("form", fields.length ? fields.map((f) => `${f.field}: ${f.reason}`).join("; ") : e.message);
    }
  };
}

/** Measured points from CSV (the columns of `knotsweep fit --points`): parameters, l_k_bar, error. */
export function readCsv(text) {
  const lines = text.split(/\r?\n/).map((l) => l.trim()).filter((l) => l && !l.startsWith("#"));
  if (!lines.length) throw new Error("no header line");
  const head = lines[0].split(",").map((c) => c.trim());
  if (!head.includes("l_k_bar") || !head.includes("error")) throw new Error("the header needs the columns l_k_bar and error");
  return lines.slice(1).map((line, k) => {
    const cells = line.split(",").map((c) => c.trim());
    if (cells.length !== head.length) throw new Error(`line ${k + 2}: ${cells.length} cells under ${head.length} columns`);
    const point = { params: {} };
    head.forEach((name, i) => {
      const v = Number(cells[i]);
      if (name === "l_k_bar" || name === "error") point[name] = v;
      else point.params[name] = Number.isNaN(v) ? cells[i] : v;
    });
    return point;
  });
}

function setError(field, text) {
  const e = document.querySelector(`.field-error[data-for="${field}"]`);
  if (e) e.textContent = text;
}

/** One fit: where its search is, the value and interval, each evaluation. */
export async function fitPage(main, id) {
  main.innerHTML = `<p><a href="#/fits">← all fits</a></p><h1>Fit ${esc(id)}</h1><div id="fit">Loading…</div>
    <section aria-labelledby="search-h"><h2 id="search-h">The search</h2><div id="fit-plot" class="plot"></div>
    <div class="table-wrap"><table><thead id="evals-head"></thead><tbody id="evals"></tbody></table></div></section>`;
  const props = await paramInfo();
  const show = async () => {
    let f;
    try {
      f = await get(`/api/fits/${id}`);
    } catch (e) {
      notice(e.message);
      return null;
    }
    const points = f.spec.points;
    const name = symbol(f.parameter, props);
    const value = f.value === null ? "" : `${esc(param(f.parameter, Number(f.value.toPrecision(4)), props))}, interval [${fmt(f.interval[0], 4)}, ${fmt(f.interval[1], 4)}]` +
      ` (χ² ${fmt(f.chi_squared, 2)} for ${points.length} points)`;
    $("#fit").innerHTML = `<p><span class="status s-${esc(f.status)}">${esc(f.status)}</span> ${value ? `· <strong id="fit-value">${value}</strong>` : ""}
      ${f.reason ? `· <strong>${esc(f.reason)}</strong>` : ""}</p>
      <p class="hint">${esc(name)} searched in [${fmt(f.range[0], 4)}, ${fmt(f.range[1], 4)}]; ${f.evaluations.length} evaluations in
      ${f.sweeps.length} sweeps (${f.sweeps.map((s) => `<a href="#/sweeps/${s}">#${s}</a>`).join(", ") || "none yet"}).</p>
      <ol class="hint">${points.map((p) => `<li>${esc(Object.entries(p.params).map(([k, v]) => param(k, v, props)).join(", ") || "the base case")}:
        measured ${LK} ${fmt(p.l_k_bar, 2)} ± ${fmt(p.error, 2)}</li>`).join("")}</ol>`;
    $("#evals-head").innerHTML = `<tr><th scope="col">${esc(name)}</th><th scope="col">weighted residual</th>${points.map((_, k) => `<th scope="col">point ${k + 1}: ${LK}</th>`).join("")}</tr>`;
    $("#evals").innerHTML = f.evaluations.map((e) => `<tr><td>${fmt(e.value, 4)}</td><td>${fmt(e.residual, 3)}</td>${e.points.map((s) =>
      `<td><a href="#/cases/${s.case_id}">${s.l_k_bar === null ? esc(s.reason || "no inversion") : fmt(s.l_k_bar, 2)}</a>${s.uncertainty !== null ? ` ± ${fmt(s.uncertainty, 2)}` : ""}</td>`).join("")}</tr>`).join("");
    if (f.evaluations.length) {
      const sorted = f.evaluations.slice().sort((a, b) => a.value - b.value);
      overlay($("#fit-plot"), {
        title: `simulated ${LK} against ${name}; dotted: the fitted value`,
        x: axisLabel(f.parameter, props),
        y: `${LK} at inversion`,
        curves: points.map((p, k) => ({ label: `point ${k + 1} (measured ${fmt(p.l_k_bar, 1)})`, colour: colour(k), dots: true,
          points: sorted.filter((e) => e.points[k].l_k_bar !== null).map((e) => [e.value, e.points[k].l_k_bar]) })),
        guides: f.value === null ? [] : [f.value],
      });
    }
    return f;
  };
  const tick = async () => {
    if (!location.hash.startsWith(`#/fits/${id}`)) return;
    const f = await show();
    if (f && f.status === "running") setTimeout(tick, 2000);
  };
  await tick();
}
