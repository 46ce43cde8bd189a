// HTTP calls to the station, with the token on every request. Errors carry the API's
// `{error, reason}` so the page can say exactly why a command was refused.

import type * as Wire from "../generated/api";
import { isObj } from "./parse";

/** Each command endpoint and its body, as the contract (../generated/api.ts) has them. */
export interface CommandBodies {
  "/api/commands/mode": Wire.ModeBody;
  "/api/commands/heading": Wire.HeadingBody;
  "/api/commands/course": Wire.CourseBody;
  "/api/commands/localizer": Wire.LocalizerBody;
  "/api/commands/target": Wire.TargetBody;
  "/api/commands/plan": Wire.PlanBody;
  "/api/cutdown/confirm": Wire.ConfirmBody;
  [param: `/api/params/${string}`]: Wire.ParamBody;
}
export type CommandPath = keyof CommandBodies;

export class ApiError extends Error {
  constructor(
    readonly status: number,
    readonly error: string,
    readonly reason: string,
  ) {
    super(status === 0 ? reason : `${status} ${error}: ${reason}`);
  }
}

export type FetchLike = (input: string, init?: RequestInit) => Promise<Response>;

export class Api {
  constructor(
    private readonly token: string | null,
    private readonly fetchFn: FetchLike = (i, init) => fetch(i, init),
  ) {}

  get<T = unknown>(path: string): Promise<T> {
    return this.request<T>("GET", path);
  }

  post<T = unknown>(path: string, body: unknown): Promise<T> {
    return this.request<T>("POST", path, body);
  }

  put<T = unknown>(path: string, body: unknown): Promise<T> {
    return this.request<T>("PUT", path, body);
  }

  delete<T = unknown>(path: string): Promise<T> {
    return this.request<T>("DELETE", path);
  }

  /** POST of a file's bytes as the raw body (a forecast file for the Plan page). */
  upload<T = unknown>(path: string, bytes: Blob): Promise<T> {
    return this.request<T>("POST", path, bytes, true);
  }

  /** POST of a command: resolves to the request id of the 202. */
  async command<P extends CommandPath>(path: P, body: CommandBodies[P]): Promise<string> {
    const r = await this.post(path, body);
    if (isObj(r) && typeof r.request_id === "string") return r.request_id;
    throw new ApiError(200, "bad_response", "no request_id in the station's answer");
  }

  private async request<T>(method: string, path: string, body?: unknown, raw = false): Promise<T> {
    const headers: Record<string, string> = { Accept: "application/json" };
    if (this.token !== null) headers.Authorization = `Bearer ${this.token}`;
    if (body !== undefined) headers["Content-Type"] = raw ? "application/octet-stream" : "application/json";
    const payload = body === undefined ? null : raw ? (body as Blob) : JSON.stringify(body);
    let res: Response;
    try {
      res = await this.fetchFn(path, { method, headers, body: payload, cache: "no-store" });
    } catch (e) {
      throw new ApiError(0, "network", `station unreachable (${e instanceof Error ? e.message : String(e)})`);
    }
    const text = await res.text();
    let json: unknown = null;
    try {
      json = text === "" ? null : JSON.parse(text);
    } catch {
      json = null;
    }
    if (!res.ok) {
      const err = isObj(json) && typeof json.error === "string" ? json.error : "http_error";
      const reason = isObj(json) && typeof json.reason === "string" ? json.reason : text.slice(0, 120) || res.statusText;
      throw new ApiError(res.status, err, reason);
    }
    return json as T;
  }
}
