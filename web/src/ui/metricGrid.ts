// A metric grid on a Leaflet map: lines every 1/2/5×10^k m east and north of an origin, about
// eight across the view, redrawn as the view moves, the lines through the origin bolder. With no
// tile loaded (an offline field, no pack) it is what still gives the map its distances. Lines
// may carry their distance from the origin ("E 500 m"); the spacing itself is told to the owner,
// whose legend names it.

import L from "leaflet";
import { fromLocal, gridValues, niceStep, toLocal } from "../lib/geo";
import type { LatLon } from "../lib/types";
import { GRID } from "./mapSymbols";

export interface GridOptions {
  /** Label each line with its distance from the origin. */
  labelLines: boolean;
  /** Called after each redraw with the spacing, m. */
  onStep?: (step_m: number) => void;
}

export class MetricGrid {
  private readonly layer = L.layerGroup();
  /** The spacing last drawn, m (0 before the first). */
  step_m = 0;

  constructor(
    private readonly map: L.Map,
    private origin: LatLon,
    private readonly options: GridOptions,
  ) {
    this.layer.addTo(map);
    map.on("moveend zoomend", () => this.draw());
  }

  /** Lines through a new origin (the recovery page learns it after the map is made). */
  setOrigin(origin: LatLon): void {
    this.origin = origin;
    this.draw();
  }

  draw(): void {
    this.layer.clearLayers();
    const b = this.map.getBounds();
    const sw = toLocal(this.origin, { lat_deg: b.getSouth(), lon_deg: b.getWest() });
    const ne = toLocal(this.origin, { lat_deg: b.getNorth(), lon_deg: b.getEast() });
    const step = niceStep(Math.max(ne.east_m - sw.east_m, ne.north_m - sw.north_m), 8);
    const pt = (east_m: number, north_m: number): L.LatLngExpression => {
      const p = fromLocal(this.origin, { east_m, north_m });
      return [p.lat_deg, p.lon_deg];
    };
    // Leaflet positions the icon element with its own transform: offsets go on the inner span.
    const label = (text: string, at: L.LatLngExpression, cls: string): L.Marker =>
      L.marker(at, { icon: L.divIcon({ className: "grid-label", html: `<span class="${cls}">${text}</span>`, iconSize: [0, 0] }), interactive: false, keyboard: false });
    for (const x of gridValues(sw.east_m, ne.east_m, step)) {
      this.layer.addLayer(L.polyline([pt(x, sw.north_m), pt(x, ne.north_m)], { ...GRID, weight: x === 0 ? 2 : 1 }));
      if (this.options.labelLines) this.layer.addLayer(label(`${x >= 0 ? "E" : "W"} ${Math.abs(x)} m`, pt(x, sw.north_m), "bottom"));
    }
    for (const y of gridValues(sw.north_m, ne.north_m, step)) {
      this.layer.addLayer(L.polyline([pt(sw.east_m, y), pt(ne.east_m, y)], { ...GRID, weight: y === 0 ? 2 : 1 }));
      if (this.options.labelLines) this.layer.addLayer(label(`${y >= 0 ? "N" : "S"} ${Math.abs(y)} m`, pt(sw.east_m, y), "left"));
    }
    this.step_m = step;
    this.options.onStep?.(step);
  }
}
