import { describe, expect, it } from "vitest";
import { learnedTable, type LearnedTable } from "./learned";
import type { Learned } from "./types";

// API.md's example: the canopy flies a little slow and sinks a little fast, turns a little slowly.
const LEARNED: Learned = { brake: [0, 0.5, 1], airspeed_scale: [0.97, 0.97, 0.97], sink_scale: [1.08, 1.1, 1.12], learned_s: 84, turn_scale: 0.91, turn_learned_s: 36.5, flying: true, airspeed_sigma: 0.012, sink_sigma: 0.018, turn_sigma: 0.04 };

const texts = (t: LearnedTable): string[][] => [t.head, ...t.rows].map((r) => r.map((c) => c.text));
/** Columns each row fills, spans counted, the cells that a row span above reaches included. */
const widths = (t: LearnedTable): number[] => {
  const width = (r: LearnedTable["head"]): number => r.reduce((n, c) => n + (c.cols ?? 1), 0);
  const carried = t.rows[0].filter((c) => (c.rows ?? 1) === 2).reduce((n, c) => n + (c.cols ?? 1), 0);
  return [width(t.head), width(t.rows[0]), width(t.rows[1]) + carried];
};

describe("the learned polar's table", () => {
  it("learned: each brake setting's airspeed and sink in percent of nominal, the turn, and the seconds behind each", () => {
    const t = learnedTable(LEARNED);
    expect(texts(t)).toEqual([
      ["learned 84 s", "brakes 0", "½", "1", "turn 37 s"],
      ["airspeed", "97 %", "97 %", "97 %", "91 %"],
      ["sink", "108 %", "110 %", "112 %"],
    ]);
    expect([...t.head, ...t.rows.flat()].some((c) => c.off)).toBe(false);
    expect(t.rows[0][1]?.title).toBe("airspeed at brakes 0: 97.0 % of nominal ± 1.2 % (1σ)");
    expect(t.rows[1][2]?.title).toBe("sink rate at brakes ½: 110.0 % of nominal ± 1.8 % (1σ)");
    expect(t.rows[0][4]?.title).toBe("turn rate: 91.0 % of nominal ± 4.0 % (1σ)");
    // No σ received: the figure alone.
    expect(learnedTable({ ...LEARNED, sink_sigma: null }).rows[1][1]?.title).toBe("sink rate at brakes 0: 108.0 % of nominal");
  });

  it("more than 15 % from nominal, either way, stands out, and not by colour alone", () => {
    const t = learnedTable({ ...LEARNED, airspeed_scale: [0.84, 0.85, 1.0], sink_scale: [1.16, 1.15, 1.3], turn_scale: 0.6 });
    expect(texts(t).slice(1)).toEqual([["airspeed", "84 %!", "85 %", "100 %", "60 %!"], ["sink", "116 %!", "115 %", "130 %!"]]);
    expect(t.rows.map((r) => r.slice(1).map((c) => c.off === true))).toEqual([[true, false, false, true], [true, false, true]]);
    expect(t.rows[1][3]?.title).toBe("sink rate at brakes 1: 130.0 % of nominal ± 1.8 % (1σ), more than 15 % off");
  });

  it("nothing learned yet: says so, no percentages (the scales are still the polar's)", () => {
    for (const none of [{ learned_s: 0, turn_learned_s: 0 }, { learned_s: null, turn_learned_s: null }]) {
      const t = learnedTable({ ...LEARNED, airspeed_scale: [1, 1, 1], sink_scale: [1, 1, 1], turn_scale: 1, ...none });
      expect(texts(t)).toEqual([["learned", "brakes 0", "½", "1", "turn"], ["airspeed", "not learned yet", "not yet"], ["sink"]]);
      expect(t.rows[0][1]).toMatchObject({ cols: 3, rows: 2 });
    }
  });

  it("the turn learned before the glide, and the glide before the turn, each on its own", () => {
    expect(texts(learnedTable({ ...LEARNED, learned_s: 0, turn_learned_s: 0.25 }))).toEqual([["learned", "brakes 0", "½", "1", "turn 0.3 s"], ["airspeed", "not learned yet", "91 %"], ["sink"]]);
    expect(texts(learnedTable({ ...LEARNED, turn_learned_s: 0 }))[1]).toEqual(["airspeed", "97 %", "97 %", "97 %", "not yet"]);
  });

  it("no learned block (guidance not flying its spiral): no figure at all, and it says why", () => {
    const t = learnedTable(null);
    expect(texts(t)).toEqual([["learned", "brakes 0", "½", "1", "turn"], ["airspeed", "— guidance replica not flying"], ["sink"]]);
    expect(t.rows.flat().some((c) => /%/.test(c.text))).toBe(false);
  });

  it("after the landing: the flight's last values stay, headed as such, the seconds behind them in the title", () => {
    const t = learnedTable({ ...LEARNED, flying: false });
    expect(texts(t)).toEqual([
      ["at landing", "brakes 0", "½", "1", "turn 37 s"],
      ["airspeed", "97 %", "97 %", "97 %", "91 %"],
      ["sink", "108 %", "110 %", "112 %"],
    ]);
    expect(t.head[0]?.title).toMatch(/^as last learned before the landing, from 84 s of straight, settled flight: /);
  });

  it("a scale the parser could not read shows a dash, not a number", () => {
    const t = learnedTable({ ...LEARNED, sink_scale: null, turn_scale: null });
    expect(texts(t).slice(1)).toEqual([["airspeed", "97 %", "97 %", "97 %", "—"], ["sink", "—", "—", "—"]]);
  });

  it("keeps one shape in every case: the left column's layout never jumps", () => {
    const cases = [LEARNED, { ...LEARNED, flying: false }, { ...LEARNED, learned_s: 0 }, { ...LEARNED, turn_learned_s: 0 }, { ...LEARNED, learned_s: 0, turn_learned_s: 0 }, null];
    for (const l of cases) expect(widths(learnedTable(l))).toEqual([5, 5, 5]);
  });
});
