// Minimal accessible tabs: one panel visible at a time; `onShow` lets charts and WebGL size
// themselves once they are visible (they cannot measure a hidden element).

import { h } from "./dom";

export interface Tab {
  id: string;
  label: string;
  content: HTMLElement;
  onShow?: () => void;
}

export function tabs(name: string, list: Tab[]): { root: HTMLElement; show: (id: string) => void } {
  const bar = h("div", { class: "tabbar", role: "tablist", "aria-label": name });
  const body = h("div", { class: "tabbody" });
  const buttons = new Map<string, HTMLButtonElement>();
  const show = (id: string): void => {
    for (const t of list) {
      const on = t.id === id;
      t.content.hidden = !on;
      buttons.get(t.id)?.setAttribute("aria-selected", String(on));
      buttons.get(t.id)?.classList.toggle("on", on);
    }
    const t = list.find((x) => x.id === id);
    if (t?.onShow) requestAnimationFrame(() => t.onShow?.());
  };
  for (const t of list) {
    const b = h("button", { type: "button", role: "tab", "data-testid": `tab-${t.id}`, "aria-controls": `tabpanel-${t.id}` }, t.label);
    b.addEventListener("click", () => show(t.id));
    buttons.set(t.id, b);
    bar.append(b);
    t.content.setAttribute("role", "tabpanel");
    t.content.id = `tabpanel-${t.id}`;
    body.append(t.content);
  }
  show(list[0]?.id ?? "");
  return { root: h("div", { class: `tabs tabs-${name}` }, bar, body), show };
}
