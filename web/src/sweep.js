// A sweep: live progress (server-sent events), F bar and H bar of every
// finished case overlaid (paper Figs 6/8/10 a, b), the phase diagram
// (Figs 7/9/11; a certified sweep's with error bars from the refined twins),
// the cases, and downloads.
import { api, get, limits, paramInfo } from "./api.js";
import { esc, fmt, duration, when, notice, colour, download, PALETTE, $, LK, FB, HB, param, axisLabel, axisValue, symbol } from "./util.js";
import { overlay, scatter } from "./plot.js";
import { stageCurves } from "./stages.js";

/** Cases overlaid at most (the first ones in grid order). */
const MAX_CURVES = 40;
let source = null;

export async function sweepPage(main, id) {
  main.innerHTML = `
    <p><a href="#/">← all sweeps</a></p>
    <h1 id="title">Sweep #${esc(id)}</h1>
    <div id="summary" aria-live="polite">Loading…</div>
    <div class="actions" id="actions"></div>
    <section aria-labelledby="curves-h"><h2 id="curves-h">Loading curves</h2>
      <div class="plots"><div id="plot-f" class="plot"></div><div id="plot-h" class="plot"></div></div></section>
    <section aria-labelledby="phase-h"><h2 id="phase-h">Phase diagram</h2><div id="phase" class="plot"></div>
      <p class="hint" id="phase-note"></p>
      <form id="measured-form" class="measured"><label for="measured-file">Measured inversions beside the simulation
        (CSV: the varied parameter in SI units, <code>l_k_bar</code>, <code>error</code>)</label>
        <input id="measured-file" type="file" accept=".csv,text/csv"> <span id="measured-note" class="hint" role="status"></span></form></section>
    <section aria-labelledby="map-h" id="map-section" hidden><h2 id="map-h">Map over both axes</h2>
      <p><a id="map-link" href="#/sweeps/${esc(id)}/map">the map's page: refine where the outcome changes</a></p>
      <img id="map" class="map" alt="the critical l_k bar over the sweep's two axes"></section>
    <section aria-labelledby="cases-h"><h2 id="cases-h">Cases</h2>
      <div class="table-wrap"><table><thead><tr><th scope="col">Case</th><th scope="col">Parameters</th><th scope="col">Status</th>
        <th scope="col">Progress</th><th scope="col">Inversion ${LK}</th><th scope="col">Wall time</th></tr></thead>
        <tbody id="cases"></tbody></table></div></section>
    <section aria-labelledby="dl-h"><h2 id="dl-h">Downloads</h2>
      <p id="downloads"><a href="/api/sweeps/${esc(id)}/phase-diagram.csv" download="sweep-${esc(id)}-phase-diagram.csv">phase diagram (CSV)</a> ·
      <a href="/api/sweeps/${esc(id)}/phase-diagram" download="sweep-${esc(id)}-phase-diagram.json">phase diagram (JSON)</a> ·
      <button type="button" id="all-csv">all series (CSV)</button> ·
      ${FB} figure <a href="/api/sweeps/${esc(id)}/figures/F_bar.svg" download="sweep-${esc(id)}-F_bar.svg">SVG</a>,
      <a href="/api/sweeps/${esc(id)}/figures/F_bar.pdf" download="sweep-${esc(id)}-F_bar.pdf">PDF</a> ·
      ${HB} figure <a href="/api/sweeps/${esc(id)}/figures/H_bar.svg" download="sweep-${esc(id)}-H_bar.svg">SVG</a>,
      <a href="/api/sweeps/${esc(id)}/figures/H_bar.pdf" download="sweep-${esc(id)}-H_bar.pdf">PDF</a>
      <span id="phase-svg"></span> ·
      <a href="/api/sweeps/${esc(id)}">sweep (JSON)</a></p></section>`;
  const state = { id, seriesOf: new Map(), drawn: "" };
  $("#all-csv").onclick = () => allSeries(state);
  $("#measured-file").onchange = async (e) => {
    const file = e.target.files[0];
    if (!file) return;
    try {
      const points = (await api("PUT", `/api/sweeps/${id}/measurements`, { csv: await file.text() })).body;
      $("#measured-note").textContent = `${points.length} measured points drawn.`;
      state.drawn = "";
      refresh(state);
    } catch (err) {
      $("#measured-note").textContent = err.fields && err.fields.length ? err.fields.map((f) => `${f.field}: ${f.reason}`).join("; ") : err.message;
    }
  };
  await refresh(state);
  if (source) source.close();
  source = new EventSource(`/api/sweeps/${id}/events`);
  let pending = null;
  const later = () => {
    if (location.hash.replace(/\/$/, "") !== `#/sweeps/${id}`) { source.close(); return; }
    clearTimeout(pending);
    pending = setTimeout(() => refresh(state), 300);
  };
  source.addEventListener("progress", later);
  source.addEventListener("done", () => { later(); source.close(); });
}

async function refresh(state) {
  const { id } = state;
  let sweep, all, pd, served, props, measured;
  try {
    served = await limits();
    [sweep, all, pd, props, measured] = await Promise.all([
      get(`/api/sweeps/${id}`), get(`/api/sweeps/${id}/cases?limit=${served.max_page}`), get(`/api/sweeps/${id}/phase-diagram`),
      paramInfo(), get(`/api/sweeps/${id}/measurements`),
    ]);
  } catch (e) {
    notice(e.message);
    return;
  }
  // A certified sweep's refined twins (time step halved) are cases too: listed
  // after their point, not drawn as points or curves of their own.
  const pointIds = new Set(pd.points.map((p) => p.case_id));
  const isTwin = (c) => c.twin_of !== null && c.twin_of !== undefined && !pointIds.has(c.case_id);
  const cases = all.filter((c) => !isTwin(c));
  const twinsOf = new Map();
  for (const c of all.filter(isTwin)) twinsOf.set(c.twin_of, [...(twinsOf.get(c.twin_of) || []), c]);
  const uncertaintyOf = new Map(pd.points.map((p) => [p.case_id, settled(p)]));
  $("#title").textContent = `Sweep #${sweep.id} ${sweep.name || sweep.preset || ""}`;
  $("#phase-svg").innerHTML = sweep.varied.length
    ? ` · phase diagram <a href="/api/sweeps/${esc(id)}/figures/phase.svg" download="sweep-${esc(id)}-phase.svg">SVG</a>,
      <a href="/api/sweeps/${esc(id)}/figures/phase.pdf" download="sweep-${esc(id)}-phase.pdf">PDF</a>` : "";
  $("#measured-form").hidden = !sweep.varied.length;
  if (sweep.varied.length >= 2) {
    // The map (server-drawn SVG), fetched again as points finish.
    const done = all.filter((c) => c.progress >= 1).length;
    const src = `/api/sweeps/${id}/figures/map.svg?finished=${done}`;
    $("#map-section").hidden = false;
    if ($("#map").getAttribute("src") !== src) $("#map").setAttribute("src", src);
    $("#phase-svg").innerHTML += ` · map <a href="/api/sweeps/${esc(id)}/figures/map.svg" download="sweep-${esc(id)}-map.svg">SVG</a>,
      <a href="/api/sweeps/${esc(id)}/figures/map.pdf" download="sweep-${esc(id)}-map.pdf">PDF</a>`;
  }
  const counts = Object.entries(sweep.counts).map(([k, v]) => `${esc(k)} ${v}`).join(", ");
  $("#summary").innerHTML = `<p><span class="status s-${esc(sweep.status)}">${esc(sweep.status)}</span>
    <progress max="1" value="${sweep.progress}" aria-label="sweep progress"></progress> ${fmt(100 * sweep.progress, 0)} %
    ${sweep.eta_seconds === null ? "" : `· ETA ${duration(sweep.eta_seconds)}`} · ${sweep.total} cases (${counts})${pd.certified ? ` · certified: ${cases.length} points and their refined twins` : ""} · varied: ${esc(sweep.varied.map((v) => symbol(v, props)).join(", ") || "none")}
    · created ${when(sweep.created_at)}</p>`;
  const live = sweep.state !== "cancelled" && sweep.status !== "done";
  $("#actions").innerHTML = live
    ? (sweep.state === "paused" ? `<button type="button" data-a="resume">Resume</button>` : `<button type="button" data-a="pause">Pause</button>`) +
      ` <button type="button" data-a="cancel">Cancel</button>`
    : "";
  for (const b of document.querySelectorAll("#actions button")) {
    b.onclick = async () => {
      try { await api("POST", `/api/sweeps/${id}/${b.dataset.a}`, {}); notice(""); } catch (e) { notice(e.message); }
      refresh(state);
    };
  }
  const axisName = sweep.varied[0];
  const params = (c) => esc(Object.entries(c.params).map(([k, v]) => param(k, v, props)).join(", ") || "the base case");
  const rest = (c, inversion) => `
    <td><span class="status s-${esc(c.status)}">${esc(c.status)}</span>${c.reason ? ` <span class="hint">${esc(c.reason)}</span>` : ""}</td>
    <td><progress max="1" value="${c.progress}" aria-label="case ${c.case_id} progress"></progress></td>
    <td>${inversion}</td><td>${c.wall_time ? duration(c.wall_time) : "–"}</td></tr>`;
  const plusMinus = (c) => {
    const u = uncertaintyOf.get(c.case_id);
    return u && u.absolute !== null ? ` ± ${fmt(u.absolute, 2)}` : "";
  };
  $("#cases").innerHTML = cases.map((c, i) => `<tr>
    <td><a href="#/cases/${c.case_id}"><span class="swatch c${i % PALETTE.length}"></span>case ${c.case_id}</a></td>
    <td>${params(c)}</td>${rest(c, c.inversion ? fmt(c.inversion.l_k_bar) + plusMinus(c) : "–")}` +
    (twinsOf.get(c.case_id) || []).map((t) => `<tr class="twin">
    <td><a href="#/cases/${t.case_id}">case ${t.case_id}</a> <span class="twin-of">refined twin of #${c.case_id}</span></td>
    <td>${params(t)}, time step halved</td>${rest(t, t.inversion ? fmt(t.inversion.l_k_bar) : "–")}`).join("")).join("");
  // Curves of the finished cases (fetched once each).
  const finished = cases.slice(0, MAX_CURVES).filter((c) => c.progress >= 1 || c.wall_time);
  await Promise.all(finished.filter((c) => !state.seriesOf.has(c.case_id)).map(async (c) => {
    const detail = await get(`/api/cases/${c.case_id}`);
    state.seriesOf.set(c.case_id, { series: detail.series || [], params: detail.params });
  }));
  const key = finished.map((c) => c.case_id).join(",");
  if (key !== state.drawn) {
    state.drawn = key;
    const label = (c) => Object.entries(c.params).map(([k, v]) => param(k, v, props)).join(", ") || `case ${c.case_id}`;
    // One curve per stage of each case's program, in the case's colour: tightening solid, loosening dashed.
    const curves = (pick) => finished.flatMap((c) => {
      const { series, params } = state.seriesOf.get(c.case_id) || { series: [], params: null };
      const drawn = stageCurves(series, params, pick, colour(cases.indexOf(c)),
        (run, n) => (n === 1 ? label(c) : `${label(c)}, ${run.stage + 1}. ${run.kind}`));
      if (drawn.length) drawn[0].mark = c.inversion ? c.inversion.l_k_bar : null;
      return drawn;
    });
    if (finished.length) {
      const loosens = finished.some((c) => (state.seriesOf.get(c.case_id)?.params?.loading || []).some((st) => "release" in st));
      const styles = loosens ? "vertical dashes: inversion; dashed curves: loosening" : "dashed: inversion";
      const guides = measured.map((m) => m.l_k_bar);
      const more = guides.length ? "; dotted black: measured" : "";
      overlay($("#plot-f"), { title: `${FB} against ${LK} (${styles}${more})`, x: LK, y: `${FB} = F h² / EI`, curves: curves((s) => s.F_bar), guides });
      overlay($("#plot-h"), { title: `${HB} against ${LK} (${styles}${more})`, x: LK, y: `${HB} = H / W`, curves: curves((s) => s.H_bar), guides });
    } else {
      $("#plot-f").textContent = "Curves appear as cases finish.";
    }
  }
  if (axisName) {
    const scale = axisName === "h" ? 1e3 : 1;
    const shown = (p) => param(axisName, p.params[axisName], props);
    // Snaps nearly always release the pull (F bar falls). An event through which
    // F bar keeps rising is drawn hollow and listed with its kinetic-energy
    // ratio, which tells a snap from a loop lying down (docs/FIDELITY.md).
    const inverted = pd.points.filter((p) => p.inversion);
    const rising = (p) => p.inversion.F_bar_after >= p.inversion.F_bar_before;
    const at = (p) => [Number(p.params[axisName]) * scale, p.inversion.l_k_bar];
    const points = inverted.filter((p) => !rising(p)).map(at);
    const loaded = inverted.filter(rising).map(at);
    // The simplified model applies against n and h (the paper's Figs 14 and 15).
    const reference = axisName === "n" || axisName === "h"
      ? pd.points.filter((p) => p.simplified_l_k_bar !== null).map((p) => [Number(p.params[axisName]) * scale, p.simplified_l_k_bar])
      : [];
    // Certified: l_k bar +- |refined twin - point|, and a red ring where they
    // differ by more than the service's threshold (or only one of the two inverts).
    const errors = inverted.filter((p) => settled(p) && p.uncertainty.absolute !== null)
      .map((p) => [...at(p), p.uncertainty.absolute]);
    const unconverged = inverted.filter((p) => settled(p) && p.uncertainty.converged === false).map(at);
    // A program that loosens: the second fold (the flip back) and the band of hysteresis between the folds.
    const xOf = (p) => Number(p.params[axisName]) * scale;
    const flipped = pd.points.filter((p) => p.hysteresis);
    const flips = flipped.map((p) => [xOf(p), p.hysteresis.flip_back_l_k_bar]);
    const band = flipped.map((p) => [xOf(p), p.hysteresis.inversion_l_k_bar, p.hysteresis.flip_back_l_k_bar]);
    const unsteady = inverted.filter((p) => p.quasi_static && p.quasi_static.holds === false).map(at);
    const integer = props[axisName] && props[axisName].type === "integer";
    scatter($("#phase"), {
      title: `critical ${LK} against ${symbol(axisName, props)}`,
      x: axisLabel(axisName, props),
      y: `critical ${LK}`,
      integer,
      measured: measured.filter((m) => m.params[axisName] !== undefined).map((m) => [axisValue(axisName, m.params[axisName]), m.l_k_bar, m.error]),
      points,
      loaded,
      reference,
      errors,
      unconverged,
      flips,
      band,
      unsteady,
    });
    const none = pd.points.filter((p) => !p.inversion).map((p) => `${shown(p)}: ${p.reason || p.status}`);
    const held = inverted.filter(rising).map((p) => `${shown(p)} (${FB} × ${fmt(p.inversion.F_bar_after / p.inversion.F_bar_before, 3)}, kinetic energy × ${fmt(p.inversion.kinetic_energy_ratio, 1)})`);
    // Fig. 11's axis: what the model gives there (docs/FIDELITY.md).
    const friction = axisName === "mu"
      ? `Paper Fig. 11: the loop inverts earlier, at a larger ${LK}, as μ grows. The default model (friction at the centre lines, the paper's start twist) gives that trend with a clean snap at every mu; with rolling = true the high-friction points lose their snap (docs/FIDELITY.md).`
      : "";
    const widths = flipped.map((p) => `${shown(p)}: ${fmt(p.hysteresis.width, 1)}`);
    const fast = pd.points.filter((p) => p.quasi_static && p.quasi_static.holds === false)
      .map((p) => `${shown(p)} (kinetic / elastic ${fmt(p.quasi_static.kinetic_ratio, 4)} > ${fmt(p.quasi_static.limit, 4)})`);
    $("#phase-note").textContent = [
      friction,
      flips.length ? `Hysteresis (shaded between the tightening inversion and the flip back while loosening): width in ${LK} ${widths.join("; ")}.` : "",
      fast.length ? `Not quasi-static (ringed orange: the pull was too fast for the rod, its curves carry inertia): ${fast.join("; ")}.` : "",
      certification(pd, served, shown),
      none.length ? "Without an inversion: " + none.join("; ") + "." : "",
      held.length ? `${FB} does not fall through the event at ` + held.join("; ") +
        ". A kinetic energy tens of times its median marks a snap; 5-10 times marks a loop lying down while the pull keeps loading it (docs/FIDELITY.md)." : "",
    ].filter(Boolean).join(" ");
  } else {
    const p = pd.points[0];
    $("#phase").textContent = p && p.inversion ? `Inversion at ${LK} ${fmt(p.inversion.l_k_bar)}${plusMinus(p)}` +
      (p.hysteresis ? `; flip back at ${fmt(p.hysteresis.flip_back_l_k_bar)} (hysteresis width ${fmt(p.hysteresis.width)})` : "") +
      (p.quasi_static && p.quasi_static.holds === false ? "; not quasi-static" : "") : "A single case: no axis to plot.";
    $("#phase-note").textContent = certification(pd, served, () => "the case");
  }
}

/** A point's uncertainty once both it and its refined twin have finished, else null. */
function settled(p) {
  const u = p.uncertainty;
  return u && u.converged !== null && p.status !== "queued" && p.status !== "running" ? u : null;
}

/** The note on a certified sweep's uncertainties: the unconverged points, and the twins still running. */
function certification(pd, served, name) {
  if (!pd.certified) return "";
  const threshold = `${fmt(100 * served.converged_within, 1)} %`;
  const pending = pd.points.filter((p) => !settled(p)).length;
  const why = (u) => u.relative !== null ? `the refined twin differs by ${fmt(100 * u.relative, 1)} %`
    : u.refined_l_k_bar !== null ? "only the refined twin inverts" : "the refined twin does not invert";
  const flagged = pd.points.filter((p) => settled(p) && p.uncertainty.converged === false)
    .map((p) => `${name(p)} (${why(p.uncertainty)})`);
  return [
    `Certified: error bars are ± the change of the inversion's ${LK} when the time step is halved (each point's refined twin).`,
    flagged.length ? `Unconverged (ringed red: more than ${threshold} apart, or only one of the two inverts): ${flagged.join("; ")}.` : "",
    !pending ? "" : pd.complete ? `Without an uncertainty: ${pending} of ${pd.points.length} points (they or their refined twins have no result).`
      : `Still running: ${pending} of ${pd.points.length} points or their refined twins; the error bars appear as both finish.`,
    pending || flagged.length ? "" : `Every point converged within ${threshold}.`,
  ].filter(Boolean).join(" ");
}

async function allSeries(state) {
  const cases = await get(`/api/sweeps/${state.id}/cases?limit=${(await limits()).max_page}`);
  let out = "";
  for (const c of cases) {
    const r = await fetch(`/api/cases/${c.case_id}/series.csv`);
    if (!r.ok) continue;
    const lines = (await r.text()).trim().split("\n");
    if (!out) out = "case_id," + lines[0] + "\n";
    out += lines.slice(1).map((l) => `${c.case_id},${l}`).join("\n") + "\n";
  }
  download(`sweep-${state.id}-series.csv`, out, "text/csv");
}
