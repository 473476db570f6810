"""Seed 000's multiple-hypothesis mode of the bearing tracker: hypotheses, IMM models,
track arrays, resolution conflicts and retrodiction. Pure."""
