// A case: status and reason, the knot in 3D with a slider through the stored
// snapshots (synchronised with a cursor on the F bar / H bar plots; the
// inversion's snapshot marked), the series and downloads.
import { get, paramInfo, snapshotLabels } from "./api.js";
import { esc, fmt, duration, notice, $, LK, FB, HB, param } from "./util.js";
import { overlay } from "./plot.js";
import { KnotView } from "./knot3d.js";
import { program, stageCurves, stageKind, direction } from "./stages.js";

/** The parameters that say which knot a case ties: n for the overhand, the knot's name (and its word or pole) for any other. */
const knotKeys = (p) =>
  !p.knot || p.knot === "overhand"
    ? ["n"]
    : ["knot", ...(p.knot === "braid" ? ["braid_word"] : []), ...(p.knot === "clove_hitch" ? ["cylinder_radius"] : [])];

/** An event's kind in words. */
const EVENT_WORDS = { inversion: "inversion", flip_back: "flip back", snap: "snap", slip_through: "slip through" };

/** A stage's given fields as text (" to_l_k_bar 120"), its null ones left out. */
const stageArgs = (stage) => Object.entries(Object.values(stage)[0] || {})
  .filter(([, v]) => v !== null && v !== undefined).map(([k, v]) => ` ${esc(k)} ${esc(v)}`).join(",");

export async function casePage(main, id) {
  main.innerHTML = `<p><a href="#/">← all sweeps</a> <span id="back"></span></p><h1>Case ${esc(id)}</h1><div id="case">Loading…</div>`;
  let c, snapshots, props, labels;
  try {
    [c, snapshots, props, labels] = await Promise.all([get(`/api/cases/${id}`), get(`/api/cases/${id}/snapshots`).catch(() => []), paramInfo(),
      snapshotLabels()]);
  } catch (e) {
    notice(e.message);
    return;
  }
  if (c.sweeps.length) $("#back").innerHTML = `· <a href="#/sweeps/${c.sweeps[0]}">sweep #${c.sweeps[0]}</a>`;
  const r = c.result;
  const inv = r && r.inversion;
  const p = c.params;
  const summary = (r && r.summary) || {};
  const events = summary.events || [];
  const hysteresis = summary.hysteresis || null;
  const quasi = summary.quasi_static || null;
  const stages = program(p);
  snapshots = (snapshots || []).slice().sort((a, b) => b.l_k_bar - a.l_k_bar);
  // The snapshot at each event is marked; the slider starts at the first event's.
  const about = (f) => labels[f.label] || { description: f.label, event: null, at_event: false };
  const firstEvent = events[0];
  // A hitch's rigid cylinder, where the result gives one.
  const cylinder = (r && ((r.summary && r.summary.cylinder) || r.cylinder)) || null;
  // A bend's or a hitch's holding force (the largest F bar before the rods part) and whether it still holds.
  const holding = typeof summary.holding_force_bar === "number" ? { force: summary.holding_force_bar, tied: summary.tied } : null;
  const atEvent = snapshots.findIndex((f) => about(f).at_event && (!firstEvent || about(f).event === firstEvent.kind));
  const invIndex = atEvent >= 0 ? atEvent : snapshots.findIndex((f) => about(f).at_event);
  $("#case").innerHTML = `
    <p><span class="status s-${esc(c.status)}">${esc(c.status)}</span>
      ${r && r.reason ? `<strong>${esc(r.reason)}</strong>` : c.last_error ? `<strong>${esc(c.last_error)}</strong>` : ""}
      ${inv ? ` · inversion at ${LK} ${fmt(inv.l_k_bar, 2)} (l_c/L ${fmt(inv.l_c_over_L, 3)}), ${FB} ${fmt(inv.F_bar_before, 4)} → ${fmt(inv.F_bar_after, 4)}, ${HB} ${fmt(inv.H_bar_before, 3)} → ${fmt(inv.H_bar_after, 3)}` : r && !holding ? " · no inversion" : ""}
      ${holding ? `<span id="holding"> · holding force ${FB} ${fmt(holding.force, 4)}${holding.tied === false ? ", slipped through" : holding.tied ? ", still tied" : ""}</span>` : ""}
      ${r ? ` · ${duration(r.wall_time)} on ${esc(r.worker)}` : ` · progress ${fmt(100 * c.progress, 0)} %`}</p>
    <p class="hint" id="held">${esc([...knotKeys(p), "h", "mu", "length", "youngs_modulus", "density", "poisson_ratio"].map((k) => param(k, p[k], props)).join(", "))},
      K = ${c.nodes} nodes${p.nodes === null ? " (the default for this rod)" : ""}; attempts ${c.attempts} of ${c.max_attempts}</p>
    ${quasi && quasi.holds === false ? `<p class="warning" id="not-quasi-static" role="note">Not quasi-static: the kinetic energy was ${fmt(quasi.kinetic_ratio, 4)} of the elastic energy
      (median before each event), over the limit of ${fmt(quasi.limit, 4)}. The pull was too fast for this rod: its curves carry inertia; lower pull_speed or keep mass_scaling (docs/API.md, "Loading programs").</p>` : ""}
    <p class="hint" id="program">Loading program: ${stages.map((st, i) => `${i + 1}. ${esc(stageKind(st))} (${direction(st)})${stageArgs(st)}`).join(" → ")}${p.loading ? "" : " (the default)"}.
      ${hysteresis ? `Hysteresis: inverted at ${LK} ${fmt(hysteresis.inversion_l_k_bar, 2)} tightening, flipped back at ${fmt(hysteresis.flip_back_l_k_bar, 2)} loosening, width ${fmt(hysteresis.width, 2)}.` : ""}
      ${quasi && quasi.holds ? `Quasi-static (kinetic / elastic energy ${fmt(quasi.kinetic_ratio, 5)}, limit ${fmt(quasi.limit, 4)}).` : ""}</p>
    <section aria-labelledby="knot-h"><h2 id="knot-h">The knot</h2>
      <div id="knot" class="knot"></div>
      <div class="slider">
        <label for="snapshot">Snapshot</label>
        <input id="snapshot" type="range" min="0" max="${Math.max(0, snapshots.length - 1)}" step="1" value="${invIndex >= 0 ? invIndex : 0}" ${snapshots.length ? "" : "disabled"}>
        <output id="snapshot-label" for="snapshot"></output>
        <button type="button" id="reset">Reset view</button>
      </div>
      <p class="hint">Drag to rotate, scroll to zoom, right-drag to pan. ${snapshots.length} stored snapshots${snapshots.some((f) => about(f).at_event) ? "; each event's is marked ★" : ""}.
        Beads mark the loaded contacts, coloured from blue (weakest) to red (strongest force of the snapshot).${rodLegend(snapshots)}${cylinder ? " The grey cylinder is the hitch's rigid cylinder." : ""}</p>
    </section>
    <section aria-labelledby="curves-h"><h2 id="curves-h">Loading curves</h2>
      <p class="hint">Solid: tightening; dashed: loosening; dotted: holding or rotating. ● an inversion, ◇ a flip back.</p>
      <div class="plots"><div id="plot-f" class="plot"></div><div id="plot-h" class="plot"></div></div>
      ${events.length ? `<div class="table-wrap"><table class="events" id="events"><thead><tr><th scope="col">Stage</th><th scope="col">Event</th><th scope="col">${LK}</th>
        <th scope="col">${FB} before → after</th><th scope="col">${HB} before → after</th><th scope="col">Kinetic energy ×</th><th scope="col">Clean</th></tr></thead><tbody>
        ${events.map((e) => `<tr data-kind="${esc(e.kind)}"><td>${e.stage + 1}. ${esc(stageKind(stages[e.stage]))} (${esc(e.direction)})</td><td>${esc(EVENT_WORDS[e.kind] || e.kind)}</td>
          <td>${fmt(e.l_k_bar, 2)}</td><td>${fmt(e.F_bar_before, 4)} → ${fmt(e.F_bar_after, 4)}</td><td>${fmt(e.H_bar_before, 3)} → ${fmt(e.H_bar_after, 3)}</td>
          <td>${fmt(e.kinetic_energy_ratio, 1)}</td><td>${e.clean ? "yes" : "no"}</td></tr>`).join("")}</tbody></table></div>` : ""}
      <h3>Energies</h3><div class="plots"><div id="plot-e" class="plot"></div></div></section>
    <section aria-labelledby="dl-h"><h2 id="dl-h">Series and downloads</h2>
      <p><a href="/api/cases/${esc(id)}/series.csv" download="case-${esc(id)}.csv">series (CSV)</a> ·
        <a href="/api/cases/${esc(id)}" download="case-${esc(id)}.json">case (JSON)</a> ·
        <a href="/api/cases/${esc(id)}/snapshots" download="case-${esc(id)}-snapshots.json">snapshots (JSON)</a> ·
        ${FB} figure <a href="/api/cases/${esc(id)}/figures/F_bar.svg" download="case-${esc(id)}-F_bar.svg">SVG</a>,
        <a href="/api/cases/${esc(id)}/figures/F_bar.pdf" download="case-${esc(id)}-F_bar.pdf">PDF</a> ·
        ${HB} figure <a href="/api/cases/${esc(id)}/figures/H_bar.svg" download="case-${esc(id)}-H_bar.svg">SVG</a>,
        <a href="/api/cases/${esc(id)}/figures/H_bar.pdf" download="case-${esc(id)}-H_bar.pdf">PDF</a></p>
      <div class="table-wrap series"><table id="series"></table></div></section>`;
  const series = c.series || [];
  const label = (name) => (run, n) => n === 1 ? name : `${name}, ${run.stage + 1}. ${run.kind} (${run.direction})`;
  const marks = (field, colour) => events.map((e) => ({ x: e.l_k_bar, y: e[field], kind: e.kind, colour }));
  const f = series.length ? overlay($("#plot-f"), { title: `${FB} against ${LK}`, x: LK, y: `${FB} = F h² / EI`,
    curves: stageCurves(series, p, (s) => s.F_bar, "#0072b2", label(FB)), events: marks("F_bar_before", "#0072b2") }) : null;
  const h = series.length ? overlay($("#plot-h"), { title: `${HB} against ${LK}`, x: LK, y: `${HB} = H / W`,
    curves: stageCurves(series, p, (s) => s.H_bar, "#d55e00", label(HB)), events: marks("H_bar_before", "#d55e00") }) : null;
  if (!series.length) $("#plot-f").textContent = "No series yet.";
  energies(series);
  const cols = ["l_k_bar", "l_c_over_L", "F_bar", "H_bar", "epsilon", "phi", "contacts", "max_penetration_over_h"];
  const heads = { l_k_bar: LK, l_c_over_L: "l_c/L", F_bar: FB, H_bar: HB, epsilon: "ε", phi: "φ (rad)", contacts: "contacts", max_penetration_over_h: "largest penetration / h" };
  $("#series").innerHTML = `<thead><tr>${cols.map((k) => `<th scope="col">${heads[k]}</th>`).join("")}</tr></thead><tbody>` +
    series.filter((_, i) => i % Math.max(1, Math.ceil(series.length / 200)) === 0)
      .map((s) => `<tr>${cols.map((k) => `<td>${fmt(s[k], 3)}</td>`).join("")}</tr>`).join("") + "</tbody>";
  if (!snapshots.length) {
    $("#knot").textContent = "No snapshots stored yet (they are stored with the result).";
    return;
  }
  const view = new KnotView($("#knot"), p.h);
  view.setCylinder(cylinder);
  const slider = $("#snapshot");
  const show = () => {
    const fr = snapshots[Number(slider.value)];
    const contacts = fr.contacts || [];
    view.show(fr.points, contacts, fr.rods || []);
    const largest = contacts.length ? Math.max(...contacts.map((c) => c.force)) : 0;
    $("#snapshot-label").textContent = `${Number(slider.value) + 1}/${snapshots.length}: ${LK} ${fmt(fr.l_k_bar)} (${about(fr).description})${about(fr).at_event ? " ★" : ""}` +
      ` · ${contacts.length} loaded contacts${contacts.length ? `, largest force ${largest.toExponential(2)} N` : ""}`;
    f?.setMarker(fr.l_k_bar);
    h?.setMarker(fr.l_k_bar);
  };
  slider.oninput = show;
  $("#reset").onclick = () => view.reset();
  show();
}

/** The rods' colours in words, for a snapshot of several rods (a bend). */
const ROD_NAMES = ["blue", "orange", "green", "pink"];
function rodLegend(snapshots) {
  const rods = Math.max(0, ...snapshots.map((f) => (f.rods || []).length));
  if (rods < 2) return "";
  return ` Each rod in its own colour: ${Array.from({ length: rods }, (_, r) => `rod ${r + 1} <span class="rod-${r % ROD_NAMES.length}">${ROD_NAMES[r % ROD_NAMES.length]}</span>`).join(", ")}.`;
}

/** The energies of eq. (6) over EI / h against time: braid and loop, and stretching, bending and twisting. */
const ENERGIES = [
  ["E_braid_bar", "braid", "#0072b2", []],
  ["E_loop_bar", "loop", "#d55e00", []],
  ["E_stretch_bar", "stretching", "#009e73", [2, 3]],
  ["E_bend_bar", "bending", "#cc79a7", [2, 3]],
  ["E_twist_bar", "twisting", "#e69f00", [2, 3]],
];

function energies(series) {
  const el = $("#plot-e");
  const present = ENERGIES.filter(([k]) => series.some((s) => typeof s[k] === "number"));
  if (!series.length || !present.length) {
    el.textContent = series.length ? "This result records no energies (computed before they were)." : "No series yet.";
    return;
  }
  // Time, not l_k bar: a program that loosens or holds revisits the same l_k bar.
  overlay(el, {
    title: "Energies over EI / h against time (braid and loop solid, by energy dotted)",
    x: "time (s)",
    y: "E bar",
    curves: present.map(([k, name, colour, dash]) => ({ label: name, colour, dash, points: series.map((s) => [s.time, s[k]]) })),
  });
}
