// The access token: given once in the page URL (`?token=…`), kept in sessionStorage for reloads
// and removed from the address bar so it is not shared by copying the URL or caught in a screenshot.

export const TOKEN_KEY = "stx.token";

export interface KV {
  getItem(k: string): string | null;
  setItem(k: string, v: string): void;
}

/** Token from the query string (stored) or from storage; null if neither has one. */
export function resolveToken(search: string, storage: KV): string | null {
  const q = new URLSearchParams(search).get("token");
  if (q !== null && q !== "") {
    storage.setItem(TOKEN_KEY, q);
    return q;
  }
  const s = storage.getItem(TOKEN_KEY);
  return s === null || s === "" ? null : s;
}

/** The query string without the token (for history.replaceState). */
export function searchWithoutToken(search: string): string {
  const p = new URLSearchParams(search);
  p.delete("token");
  const s = p.toString();
  return s === "" ? "" : `?${s}`;
}

/** `path?token=…`, for the WebSocket and the KML network link, which cannot send headers. */
export function withToken(path: string, token: string | null): string {
  if (token === null) return path;
  return `${path}${path.includes("?") ? "&" : "?"}token=${encodeURIComponent(token)}`;
}
