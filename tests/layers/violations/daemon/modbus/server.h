// A header of dg_modbus.
