"""Channel plot fusion of seed 001 (modules 31-34): one base's channels fused into plots.
Pure: driven by the plots' timestamps."""
