// A header of dg_bus.
