// A header of dg_base.
