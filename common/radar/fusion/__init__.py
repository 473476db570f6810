"""Global fusion of seed 001 (modules 61-65): association of elementary tracks across
bases, initialisation by intersecting bistatic ellipses, the EKF and mixture filter,
merge, succession, segments, status and report of global tracks. Pure."""
