// knotsweep's web page: a hash router over its pages (sweeps and submission,
// a sweep and its map, a case, the fits and a fit), talking only to the public API.
import { home } from "./home.js";
import { sweepPage } from "./sweep.js";
import { casePage } from "./case.js";
import { fitsPage, fitPage } from "./fit.js";
import { mapPage } from "./map.js";
import { token } from "./api.js";
import { notice, $ } from "./util.js";

async function route() {
  const main = $("#main");
  notice("");
  const m = location.hash.match(/^#\/(sweeps|cases|fits)(?:\/(\d+))?(\/map)?/);
  try {
    if (m && m[1] === "sweeps" && m[2] && m[3]) await mapPage(main, m[2]);
    else if (m && m[1] === "sweeps" && m[2]) await sweepPage(main, m[2]);
    else if (m && m[1] === "cases" && m[2]) await casePage(main, m[2]);
    else if (m && m[1] === "fits") await (m[2] ? fitPage(main, m[2]) : fitsPage(main));
    else await home(main);
  } catch (e) {
    notice(String(e.message || e));
  }
  main.focus({ preventScroll: true });
}

$("#token").value = token.get();
$("#token-form").onsubmit = (e) => {
  e.preventDefault();
  token.set($("#token").value.trim());
  notice(token.get() ? "Token saved in this browser." : "Token removed.");
};
window.addEventListener("hashchange", route);
route();
