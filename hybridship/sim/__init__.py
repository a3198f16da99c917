"""Sea-trial simulator: environment, the "true" vessel, DP control, thrust allocation, scenarios."""
