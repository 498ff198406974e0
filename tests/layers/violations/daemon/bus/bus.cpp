#include "bus/bus.h"
// Up: dg_bus does not link dg_gateway.
#include "gateway/gateway.h"
