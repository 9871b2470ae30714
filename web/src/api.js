// The public API, with the token saved in the browser as `Authorization: Bearer`.
const TOKEN_KEY = "knotsweep-token";

export const token = {
  get: () => localStorage.getItem(TOKEN_KEY) || "",
  set: (t) => (t ? localStorage.setItem(TOKEN_KEY, t) : localStorage.removeItem(TOKEN_KEY)),
};

/** An API error: status, message and the offending fields. */
export class ApiError extends Error {
  constructor(status, body) {
    super(body && body.message ? body.message : `HTTP ${status}`);
    this.status = status;
    this.fields = (body && body.fields) || [];
  }
}

export async function api(method, path, body) {
  const headers = {};
  // The server takes every POST as JSON only (415 otherwise), a bodiless one too.
  if (method === "POST") body ??= {};
  if (body !== undefined) headers["Content-Type"] = "application/json";
  const t = token.get();
  if (t) headers["Authorization"] = "Bearer " + t;
  const r = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  const text = await r.text();
  let json = null;
  try {
    json = text ? JSON.parse(text) : null;
  } catch {
    json = { message: text };
  }
  if (!r.ok) {
    if (r.status === 401) throw new ApiError(401, { message: "401: the server requires a token; enter it above (" + (json && json.message) + ")" });
    throw new ApiError(r.status, json);
  }
  return { body: json, total: Number(r.headers.get("x-total-count") || 0) };
}

export const get = (path) => api("GET", path).then((r) => r.body);

let served = null;
/** The service's limits and certification threshold (`GET /api/limits`), fetched once. */
export function limits() {
  served ??= get("/api/limits").catch((e) => {
    served = null;
    throw e;
  });
  return served;
}

let doc = null;
/** The OpenAPI document's schemas, fetched once. */
function schemas() {
  doc ??= get("/api/openapi.json").then((d) => d.components.schemas).catch((e) => {
    doc = null;
    throw e;
  });
  return doc;
}

/**
 * Each case parameter's schema (the OpenAPI document's CaseParams properties:
 * its SI unit `x-unit`, the paper's symbol `x-symbol`, description, default),
 * fetched once.
 */
export const paramInfo = () => schemas().then((s) => s.CaseParams.properties);

/**
 * The snapshot labels (the SnapshotLabel schema's `x-labels`): for each word
 * its `description`, the `event` kind it is around (or null) and whether it
 * is the snapshot `at_event`.
 */
export const snapshotLabels = () => schemas().then((s) => s.SnapshotLabel["x-labels"]);
