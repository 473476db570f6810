// passive-fusion live view: the status palette and its shape cues (docs/view.md).
// Okabe-Ito colours chosen so that every pair, and each against the background, stays
// at CIEDE2000 >= 15 as seen with protanopia, deuteranopia and tritanopia (Machado 2009
// simulation; tests/integration/test_view_ops.py reads this palette from the page).
// Each status also has its own shape and text: a colour is never the only cue.
"use strict";

const PALETTE = {
  confirmed: "#56B4E9",  // sky blue: filled disc
  tentative: "#999999",  // grey: hollow ring
  coasting: "#F0E442",   // yellow: filled square
  ambiguous: "#D55E00",  // vermillion: dashed ring and "?"
  truth: "#FFFFFF",      // white: cross
  background: "#0b1117",
};
const SHAPES = { confirmed: "\u25cf", tentative: "\u25cb", coasting: "\u25a0", ambiguous: "?", truth: "\u00d7" };
const COLOURS = { confirmed: PALETTE.confirmed, tentative: PALETTE.tentative, coasting: PALETTE.coasting };
const AMBIGUOUS = PALETTE.ambiguous;

// CSS variables of the palette, so that legend swatches and table text use these colours
Object.entries(PALETTE).forEach(([k, v]) => document.documentElement.style.setProperty(`--${k}`, v));
