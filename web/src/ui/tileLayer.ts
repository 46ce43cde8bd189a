// The station's map tiles as a Leaflet layer, shared by the live map and the recovery page's map,
// so both ask the same source the same way (token, the pack's zoom and bounds).

import L from "leaflet";
import { withToken } from "../lib/token";
import type { Station } from "../lib/types";

/** The station's tile layer, or `null` when it configured no tile source (the grid is the map). */
export function stationTileLayer(station: Station, tileToken: string | null): L.TileLayer | null {
  if (!station.tile_url) return null;
  // Tiles are fetched by <img>, which cannot send the Authorization header: a station-relative
  // tile URL gets the token as a query parameter, like the WebSocket.
  const url = station.tile_url.startsWith("/") && tileToken !== null ? withToken(station.tile_url, tileToken) : station.tile_url;
  // A station's tile pack covers one region to one zoom: deeper, its tiles are enlarged;
  // outside, none are asked (each would be a failed tile on the badge).
  const b = station.tile_bounds;
  return L.tileLayer(url, {
    maxZoom: 19,
    attribution: station.tile_attribution,
    ...(station.tile_max_zoom !== null ? { maxNativeZoom: station.tile_max_zoom } : {}),
    ...(b !== null ? { bounds: L.latLngBounds([b[1], b[0]], [b[3], b[2]]) } : {}),
  });
}
