#include "modbus/server.h"
