"""Seed 000's bearing tracker, first embodiment (single hypothesis, GNN): model,
measurements, association, IMM, crossing (004) and memory-mode pairs, merge, history,
multi-line grouping (claims 12-13). Pure."""
