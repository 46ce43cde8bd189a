// The forecast wind profile at a given altitude, to compare with the onboard estimate.

import type { ForecastWind } from "./types";
import { wrap360 } from "./format";

export interface WindAt {
  speed_mps: number;
  from_deg: number | null;
}

/**
 * Linear interpolation in altitude; direction interpolated the short way round. Outside the
 * profile the nearest level is used (no extrapolation). `profile` is sorted by altitude.
 */
export function forecastAt(profile: readonly ForecastWind[], alt_msl_m: number): WindAt | null {
  if (profile.length === 0 || !Number.isFinite(alt_msl_m)) return null;
  const first = profile[0]!;
  const last = profile[profile.length - 1]!;
  if (alt_msl_m <= first.alt_msl_m) return { speed_mps: first.speed_mps, from_deg: first.from_deg };
  if (alt_msl_m >= last.alt_msl_m) return { speed_mps: last.speed_mps, from_deg: last.from_deg };
  for (let i = 1; i < profile.length; i++) {
    const a = profile[i - 1]!;
    const b = profile[i]!;
    if (alt_msl_m <= b.alt_msl_m) {
      const f = b.alt_msl_m === a.alt_msl_m ? 0 : (alt_msl_m - a.alt_msl_m) / (b.alt_msl_m - a.alt_msl_m);
      let from: number | null = null;
      if (a.from_deg !== null && b.from_deg !== null) {
        const d = ((b.from_deg - a.from_deg + 540) % 360) - 180;
        from = wrap360(a.from_deg + f * d);
      }
      return { speed_mps: a.speed_mps + f * (b.speed_mps - a.speed_mps), from_deg: from };
    }
  }
  return null;
}
