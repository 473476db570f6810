"""Target motion analysis: bearings-only TMA (seed 002), its Cramer-Rao bound, constrained
TMA with bounds and error handling of wrong bounds (seed 003), and the per-track manager. Pure."""
