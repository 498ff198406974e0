#include "base/log.h"
// dg_bus is not linked by drivegate.
#include "bus/bus.h"
