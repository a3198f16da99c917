"""High-speed (planing) craft: simulator, identified baselines and the residual hybrid."""
