// An adapter reaching into the daemon.
#include "modbus/server.h"
