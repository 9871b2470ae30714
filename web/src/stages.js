// A case's loading program and its series split by stage: which way each
// stage moves the clamps (solver::case::LoadStage::direction), so that plots
// draw tightening and loosening in their own styles.
import { STYLES } from "./plot.js";

/** The program a case ran: its `loading`, or the default one tightening. */
export const program = (params) => (params && Array.isArray(params.loading) && params.loading.length ? params.loading : [{ pull: {} }]);

/** A stage's kind: its one key. */
export const stageKind = (stage) => Object.keys(stage || {})[0] || "pull";

/** Which way a stage moves the clamps: pulls and soft stages tighten, releases loosen, holds and rotations keep still. */
export function direction(stage) {
  const k = stageKind(stage);
  return k === "release" ? "loosen" : k === "hold" || k === "rotate" ? "still" : "tighten";
}

/**
 * The series as runs of consecutive samples of one stage (the series' `stage`
 * column; a report without it is one stage): [{stage, kind, direction, samples}].
 */
export function runs(series, params) {
  const stages = program(params);
  const out = [];
  for (const s of series) {
    const i = Number.isInteger(s.stage) ? s.stage : 0;
    const last = out[out.length - 1];
    if (last && last.stage === i) last.samples.push(s);
    else out.push({ stage: i, kind: stageKind(stages[i]), direction: direction(stages[i]), samples: [s] });
  }
  // Each run begins where the one before ended, so that the curve is unbroken.
  for (let j = 1; j < out.length; j++) out[j].samples.unshift(out[j - 1].samples[out[j - 1].samples.length - 1]);
  return out;
}

/**
 * Curves of `pick(sample)` against l_k bar, one per stage, styled by direction.
 * `label(run)` names each; every curve takes `colour`.
 */
export function stageCurves(series, params, pick, colour, label) {
  const all = runs(series, params);
  return all.map((r) => ({
    label: label(r, all.length),
    colour,
    direction: r.direction,
    ...STYLES[r.direction],
    points: r.samples.map((s) => [s.l_k_bar, pick(s)]),
  }));
}

/** The value of `pick` at the sample nearest l_k bar `x` within `stage`'s run (the event markers' height). */
export function valueAt(series, stage, x, pick) {
  let best = null;
  for (const s of series) {
    if ((Number.isInteger(s.stage) ? s.stage : 0) !== stage) continue;
    if (best === null || Math.abs(s.l_k_bar - x) < Math.abs(best.l_k_bar - x)) best = s;
  }
  return best ? pick(best) : null;
}
