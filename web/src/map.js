// A sweep over two axes as a map (the server's SVG: colour = critical l̄_k,
// contours, points without an inversion crossed) and its refinement: the grid
// lines where the outcome changes, bisected over queued cases to a tolerance
// (POST /api/sweeps/{id}/refine), with the bracketing pair of cases of each.
import { api, get, paramInfo, ApiError } from "./api.js";
import { esc, fmt, notice, $, LK, param, symbol } from "./util.js";

const OUTCOME = { no_inversion: "no inversion", clean_snap: "clean snap", not_clean: "inversion, not clean" };

/** A distance along `axis` with its unit (h in mm). */
function distance(axis, v, props) {
  if (axis === "h") return `${Number((v * 1e3).toPrecision(4))} mm`;
  const unit = props[axis] && props[axis]["x-unit"];
  return `${Number(v.toPrecision(4))}${unit ? ` ${unit}` : ""}`;
}

export async function mapPage(main, id) {
  main.innerHTML = `
    <p><a href="#/sweeps/${esc(id)}">← sweep #${esc(id)}</a></p>
    <h1 id="map-title">Map of sweep #${esc(id)}</h1>
    <div id="map-summary" aria-live="polite">Loading…</div>
    <img id="map" class="map" alt="the critical l_k bar over the sweep's two axes">
    <p id="map-downloads">map <a href="/api/sweeps/${esc(id)}/figures/map.svg" download="sweep-${esc(id)}-map.svg">SVG</a>,
      <a href="/api/sweeps/${esc(id)}/figures/map.pdf" download="sweep-${esc(id)}-map.pdf">PDF</a> ·
      <a href="/api/sweeps/${esc(id)}/refinement">refinement (JSON)</a></p>
    <section aria-labelledby="refine-h"><h2 id="refine-h">Refine where the outcome changes</h2>
      <p class="hint">Each grid line along an axis given a tolerance, where two neighbours differ (an inversion or none, a
        clean snap or not), is bisected over queued cases until the two cases bracketing the change are within the
        tolerance. New cases are sweeps of their own, cached like any other.</p>
      <form id="refine-form" novalidate><div id="refine-fields"></div>
        <p><button type="submit">Refine</button> <span class="field-error" data-for="form" role="status"></span></p></form>
      <div id="refinement"></div>
      <div class="table-wrap"><table><thead><tr><th scope="col">Line</th><th scope="col">Lower case</th><th scope="col">Upper case</th>
        <th scope="col">Apart</th><th scope="col">Within the tolerance</th></tr></thead><tbody id="brackets"></tbody></table></div></section>`;
  const props = await paramInfo();
  const sweep = await get(`/api/sweeps/${id}`);
  if (sweep.varied.length < 2) {
    $("#map-summary").textContent = `Sweep #${id} varies ${sweep.varied.length ? symbol(sweep.varied[0], props) : "nothing"}: a map needs two axes.`;
    $("#map").hidden = true;
    return;
  }
  const numeric = sweep.varied.filter((a) => props[a] && ["number", "integer"].some((t) => [].concat(props[a].type).includes(t)));
  $("#refine-fields").innerHTML = numeric.map((a) => `<div class="field"><label for="tol-${esc(a)}">${esc(symbol(a, props))} tolerance</label>
    <span class="value"><input id="tol-${esc(a)}" inputmode="decimal" value="${a === "h" ? "0.0002" : a === "n" ? "1" : "0.02"}">
    <span class="unit">${esc((props[a] && props[a]["x-unit"]) || "")}</span></span>
    <span class="field-error" data-for="tolerance.${esc(a)}" role="status"></span></div>`).join("");
  $("#refine-form").onsubmit = async (ev) => {
    ev.preventDefault();
    for (const e of document.querySelectorAll(".field-error")) e.textContent = "";
    const tolerance = {};
    for (const a of numeric) {
      const text = $(`#tol-${a}`).value.trim();
      if (text) tolerance[a] = Number(text);
    }
    try {
      await api("POST", `/api/sweeps/${id}/refine`, { tolerance });
      last = "";
      tick();
    } catch (e) {
      const fields = e instanceof ApiError ? e.fields : [];
      for (const f of fields) {
        const slot = document.querySelector(`.field-error[data-for="${f.field}"]`);
        if (slot) slot.textContent = f.reason;
      }
      $('.field-error[data-for="form"]').textContent = fields.length ? fields.map((f) => `${f.field}: ${f.reason}`).join("; ") : e.message;
    }
  };
  let last = "";
  const show = async () => {
    let s, r = null;
    try {
      s = await get(`/api/sweeps/${id}`);
      r = await get(`/api/sweeps/${id}/refinement`).catch((e) => (e instanceof ApiError && e.status === 404 ? null : Promise.reject(e)));
    } catch (e) {
      notice(e.message);
      return null;
    }
    $("#map-title").textContent = `Map of sweep #${s.id} ${s.name || s.preset || ""}`;
    const [a, b] = s.varied;
    $("#map-summary").innerHTML = `<p><span class="status s-${esc(s.status)}">${esc(s.status)}</span> · ${s.total} cases over
      ${esc(symbol(a, props))} (across) and ${esc(symbol(b, props))} (up); the colour is each point's critical ${LK}.</p>`;
    // The figure is fetched again when a case finishes or the refinement moves on.
    const key = `${s.counts.completed || 0}-${s.progress}-${r ? `${r.status}-${r.points.length}` : "none"}`;
    if (key !== last) {
      last = key;
      $("#map").setAttribute("src", `/api/sweeps/${id}/figures/map.svg?v=${encodeURIComponent(key)}`);
    }
    if (!r) {
      $("#refinement").innerHTML = `<p class="hint">Not refined yet.</p>`;
      $("#brackets").innerHTML = `<tr><td colspan="5">No refinement.</td></tr>`;
      return ["done", "cancelled"].includes(s.status) ? null : s;
    }
    const tolerances = Object.entries(r.tolerance).map(([k, v]) => `${symbol(k, props)} to ${distance(k, v, props)}`).join(", ");
    $("#refinement").innerHTML = `<p><span class="status s-${esc(r.status)}">${esc(r.status)}</span> · ${esc(tolerances)} ·
      ${r.rounds} rounds, ${r.points.length} cases added (${r.sweeps.length} sweeps)${r.reason ? ` · <strong>${esc(r.reason)}</strong>` : ""}</p>`;
    const end = (e, axis, at) => `<a href="#/cases/${e.case_id}">case ${e.case_id}</a> at ${esc(param(axis, e.value, props))}:
      ${esc(OUTCOME[e.outcome] || e.outcome)}${e.l_k_bar === null ? "" : ` (${LK} ${fmt(e.l_k_bar, 1)})`}`;
    $("#brackets").innerHTML = r.brackets.length ? r.brackets.map((k) => `<tr>
      <td>along ${esc(symbol(k.axis, props))} at ${esc(Object.entries(k.at).map(([n, v]) => param(n, v, props)).join(", ") || "the base")}</td>
      <td>${end(k.low, k.axis, k.at)}</td><td>${end(k.high, k.axis, k.at)}</td><td>${esc(distance(k.axis, k.width, props))}</td>
      <td>${k.settled ? "yes" : k.reason ? esc(`no: ${k.reason}`) : "not yet"}</td></tr>`).join("")
      : `<tr><td colspan="5">${r.status === "running" ? "Waiting for the sweep's cases." : "The outcome is the same at every point: nothing to refine."}</td></tr>`;
    return s.status === "done" && r.status !== "running" ? null : s;
  };
  const tick = async () => {
    if (!location.hash.startsWith(`#/sweeps/${id}/map`)) return;
    if (await show()) setTimeout(tick, 2000);
  };
  await tick();
}
