"""pfusion tma: target motion analysis of the confirmed bearing tracks of one array (002, 003)."""
