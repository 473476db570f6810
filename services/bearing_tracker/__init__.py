"""``pfusion bearing-tracker``: sonar bearing tracks of one array (seed 000)."""
