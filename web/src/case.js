// A case: status and reason, the knot in 3D with a slider through the stored
// snapshots (synchronised with a cursor on the F bar / H bar plots; the
// inversion's snapshot marked), the series and downloads.
import { get } from "./api.js";
import { esc, fmt, duration, notice, $ } from "./util.js";
import { overlay } from "./plot.js";
import { KnotView } from "./knot3d.js";

const LABELS = {
  relaxed: "relaxed start",
  pull: "pulling",
  near_inversion: "approaching the inversion",
  before_inversion: "just before the inversion",
  after_inversion: "after the inversion",
  at_inversion: "inversion",
  final: "end of the pull",
  failure: "where it failed",
};

export async function casePage(main, id) {
  main.innerHTML = `<p><a href="#/">← all sweeps</a> <span id="back"></span></p><h1>Case ${esc(id)}</h1><div id="case">Loading…</div>`;
  let c, snapshots;
  try {
    [c, snapshots] = await Promise.all([get(`/api/cases/${id}`), get(`/api/cases/${id}/snapshots`).catch(() => [])]);
  } catch (e) {
    notice(e.message);
    return;
  }
  if (c.sweeps.length) $("#back").innerHTML = `· <a href="#/sweeps/${c.sweeps[0]}">sweep #${c.sweeps[0]}</a>`;
  const r = c.result;
  const inv = r && r.inversion;
  const p = c.params;
  snapshots = (snapshots || []).slice().sort((a, b) => b.l_k_bar - a.l_k_bar);
  const invIndex = snapshots.findIndex((f) => f.label === "at_inversion");
  $("#case").innerHTML = `
    <p><span class="status s-${esc(c.status)}">${esc(c.status)}</span>
      ${r && r.reason ? `<strong>${esc(r.reason)}</strong>` : c.last_error ? `<strong>${esc(c.last_error)}</strong>` : ""}
      ${inv ? ` · inversion at l_k bar ${fmt(inv.l_k_bar, 2)} (l_c/L ${fmt(inv.l_c_over_L, 3)}), F bar ${fmt(inv.F_bar_before, 4)} → ${fmt(inv.F_bar_after, 4)}, H bar ${fmt(inv.H_bar_before, 3)} → ${fmt(inv.H_bar_after, 3)}` : r ? " · no inversion" : ""}
      ${r ? ` · ${duration(r.wall_time)} on ${esc(r.worker)}` : ` · progress ${fmt(100 * c.progress, 0)} %`}</p>
    <p class="hint">n = ${p.n}, h = ${fmt(p.h * 1e3, 2)} mm, mu = ${p.mu}, L = ${p.length} m, K = ${p.nodes}; attempts ${c.attempts} of ${c.max_attempts}</p>
    <section aria-labelledby="knot-h"><h2 id="knot-h">The knot</h2>
      <div id="knot" class="knot"></div>
      <div class="slider">
        <label for="snapshot">Snapshot</label>
        <input id="snapshot" type="range" min="0" max="${Math.max(0, snapshots.length - 1)}" step="1" value="${invIndex >= 0 ? invIndex : 0}" ${snapshots.length ? "" : "disabled"}>
        <output id="snapshot-label" for="snapshot"></output>
        <button type="button" id="reset">Reset view</button>
      </div>
      <p class="hint">Drag to rotate, scroll to zoom, right-drag to pan. ${snapshots.length} stored snapshots${invIndex >= 0 ? "; the inversion's is marked ★" : ""}.
        Beads mark the loaded contacts, coloured from blue (weakest) to red (strongest force of the snapshot).</p>
    </section>
    <section aria-labelledby="curves-h"><h2 id="curves-h">Tightening curves</h2>
      <div class="plots"><div id="plot-f" class="plot"></div><div id="plot-h" class="plot"></div></div></section>
    <section aria-labelledby="dl-h"><h2 id="dl-h">Series and downloads</h2>
      <p><a href="/api/cases/${esc(id)}/series.csv" download="case-${esc(id)}.csv">series (CSV)</a> ·
        <a href="/api/cases/${esc(id)}" download="case-${esc(id)}.json">case (JSON)</a> ·
        <a href="/api/cases/${esc(id)}/snapshots" download="case-${esc(id)}-snapshots.json">snapshots (JSON)</a> ·
        <a href="/api/cases/${esc(id)}/figures/F_bar.svg" download="case-${esc(id)}-F_bar.svg">F bar figure (SVG)</a> ·
        <a href="/api/cases/${esc(id)}/figures/H_bar.svg" download="case-${esc(id)}-H_bar.svg">H bar figure (SVG)</a></p>
      <div class="table-wrap series"><table id="series"></table></div></section>`;
  const series = c.series || [];
  const mark = inv ? inv.l_k_bar : null;
  const f = series.length ? overlay($("#plot-f"), { title: "F bar against l_k bar", x: "l_k bar", y: "F bar", curves: [{ label: "F bar", colour: "#0072b2", points: series.map((s) => [s.l_k_bar, s.F_bar]), mark }] }) : null;
  const h = series.length ? overlay($("#plot-h"), { title: "H bar against l_k bar", x: "l_k bar", y: "H bar", curves: [{ label: "H bar", colour: "#d55e00", points: series.map((s) => [s.l_k_bar, s.H_bar]), mark }] }) : null;
  if (!series.length) $("#plot-f").textContent = "No series yet.";
  const cols = ["l_k_bar", "l_c_over_L", "F_bar", "H_bar", "epsilon", "phi", "contacts", "max_penetration_over_h"];
  $("#series").innerHTML = `<thead><tr>${cols.map((k) => `<th scope="col">${k}</th>`).join("")}</tr></thead><tbody>` +
    series.filter((_, i) => i % Math.max(1, Math.ceil(series.length / 200)) === 0)
      .map((s) => `<tr>${cols.map((k) => `<td>${fmt(s[k], 3)}</td>`).join("")}</tr>`).join("") + "</tbody>";
  if (!snapshots.length) {
    $("#knot").textContent = "No snapshots stored yet (they are stored with the result).";
    return;
  }
  const view = new KnotView($("#knot"), p.h);
  const slider = $("#snapshot");
  const show = () => {
    const fr = snapshots[Number(slider.value)];
    const contacts = fr.contacts || [];
    view.show(fr.points, contacts);
    const largest = contacts.length ? Math.max(...contacts.map((c) => c.force)) : 0;
    $("#snapshot-label").textContent = `${Number(slider.value) + 1}/${snapshots.length}: l_k bar ${fmt(fr.l_k_bar)} (${LABELS[fr.label] || fr.label})${fr.label === "at_inversion" ? " ★" : ""}` +
      ` · ${contacts.length} loaded contacts${contacts.length ? `, largest force ${largest.toExponential(2)} N` : ""}`;
    f?.setMarker(fr.l_k_bar);
    h?.setMarker(fr.l_k_bar);
  };
  slider.oninput = show;
  $("#reset").onclick = () => view.reset();
  show();
}
