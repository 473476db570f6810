"""Elementary tracking in bistatic coordinates (seed 001 modules 41-44): one base's
tracks [r_b, v_b, gamma_b, theta, omega] and their initiation. Pure."""
