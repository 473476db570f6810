"""Bearing-rate models of the multiple-hypothesis mode (common.sonar.mht.tracker): the two models of
the bearing tracker's IMM (common.sonar.bearing.imm: the Q of 000 with a quiet and a
manoeuvre bearing noise power, mean sojourn times), carried as a model label on every
hypothesis.

Choice (stated; 000's MHT block 42 uses "un modelo de proceso predeterminado", the one
straight-line-segment model with one Q): each cycle
every hypothesis continues in each model j with the weight c_ih p_mj (p: the Markov chain of
the models over the cycle, common.core.imm.transition; m its model) and is predicted with
the Q of model j; hypotheses of different models are never merged (the 000 hypothesis
merge runs within a track and a model), so the model branches are the MHT form of the
IMM's mixing (a generalised pseudo-Bayesian step, Bar-Shalom et al. 2001, 11.6.5). A
straight contact keeps its main hypothesis in the quiet model and a light manoeuvre copy;
at a manoeuvre the copy wins by its likelihood. With the manoeuvre Q alone the bearing
rates of crossing tracks wandered and the tracks coalesced; with the quiet Q alone no
crossing swapped but every close passage (sonar_hold_cpa) broke
(docs/decisions/012-mht-model-branches.md).
Resolution conflicts (000 IN, common.sonar.mht.tracks): the hypotheses of a track in
conflict continue in the quiet model only, as the single-hypothesis mode's IMM does in
seed 004's memory mode (common.sonar.bearing.imm): the unresolved detections between the
two targets look like a bearing-rate change to the manoeuvre model, which bent both
tracks onto one target (sonar_hold5, docs/decisions/012-mht-model-branches.md).
"""

from __future__ import annotations

import numpy as np

from common.core.imm import transition


def branch(x: np.ndarray, P: np.ndarray, c: np.ndarray, track: np.ndarray, model: np.ndarray,
           T: float, sojourn: np.ndarray, quiet: np.ndarray) -> tuple[np.ndarray, ...]:
    """Every hypothesis (x (H, n), P, weight c, track, model label) continued in each of the
    M models over a cycle of T s (the hypotheses flagged in `quiet` (H,) in the quiet model
    0 only): the branches x, P, c p_mj, track, label j, and the index of each branch's
    source hypothesis."""
    M, Hn = sojourn.size, c.size
    p = transition(np.full(Hn, T), sojourn)  # (H, M, M): p[h, i, j] = P(i -> j)
    p[quiet] = np.eye(M)[0]  # every model -> model 0
    src = np.tile(np.arange(Hn), M)
    to = np.repeat(np.arange(M), Hn)
    w = p[src, model[src], to]
    src, to, w = src[w > 0], to[w > 0], w[w > 0]
    return x[src], P[src], c[src] * w, track[src], to, src
