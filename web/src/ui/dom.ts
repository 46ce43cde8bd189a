// A few DOM helpers so panels read as structure, not as createElement noise.

type Attrs = Record<string, string | number | boolean | null | undefined | EventListener>;
type Child = Node | string | null | undefined | false;

/**
 * `h("div", {class: "x", "data-testid": "y", onclick: f}, child…)`. A `style` is set through the
 * CSSOM: the station's Content-Security-Policy refuses `style` attributes (no 'unsafe-inline').
 */
export function h<K extends keyof HTMLElementTagNameMap>(tag: K, attrs: Attrs = {}, ...children: Child[]): HTMLElementTagNameMap[K] {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === null || v === undefined || v === false) continue;
    if (k.startsWith("on") && typeof v === "function") el.addEventListener(k.slice(2), v);
    else if (k === "style") el.style.cssText = String(v);
    else if (v === true) el.setAttribute(k, "");
    else el.setAttribute(k, String(v));
  }
  for (const c of children) if (c !== null && c !== undefined && c !== false) el.append(c);
  return el;
}

const SVG_NS = "http://www.w3.org/2000/svg";

export function s<K extends keyof SVGElementTagNameMap>(tag: K, attrs: Record<string, string | number> = {}, ...children: (SVGElement | string)[]): SVGElementTagNameMap[K] {
  const el = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, String(v));
  for (const c of children) el.append(c);
  return el;
}

/** Sets text only when it changed: most readouts repeat at 4 Hz and need no layout work. */
export function setText(el: Element, text: string): void {
  if (el.textContent !== text) el.textContent = text;
}

export function setAttr(el: Element, name: string, value: string): void {
  if (el.getAttribute(name) !== value) el.setAttribute(name, value);
}

/** The style text each element was last given by `setStyle`. */
const lastStyle = new WeakMap<HTMLElement, string>();

/**
 * Sets `css` as an element's style only when it changed (readouts repeat at 4 Hz), through the
 * CSSOM: the station's Content-Security-Policy refuses `style` attributes (no 'unsafe-inline').
 */
export function setStyle(el: HTMLElement, css: string): void {
  if (lastStyle.get(el) === css) return;
  lastStyle.set(el, css);
  el.style.cssText = css;
}

/** A labelled readout: the value element carries the test id, so its text is the value alone. */
export function readout(labelText: string, testid: string, title?: string): { root: HTMLElement; value: HTMLElement } {
  const value = h("span", { class: "ro-val", "data-testid": testid });
  const root = h("div", { class: "ro", title: title ?? null }, h("span", { class: "ro-lbl" }, labelText), value);
  return { root, value };
}

/** A panel with a heading. */
export function panel(title: string, testid: string, ...children: Child[]): HTMLElement {
  return h("section", { class: "panel", "data-testid": testid, "aria-label": title }, h("h2", {}, title), ...children);
}
