// A header of dg_gateway.
