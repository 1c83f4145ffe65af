"""openbricks_sim: MuJoCo worlds, the driver shim and virtual hubs that run hub programs unchanged."""
