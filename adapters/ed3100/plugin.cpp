// The ed3100 plugin descriptor.
#include "drivegate/adapter.h"
#include "schema.h"

// Line: the document offers 8N2, 8E1 and 8O1 and leaves the baud rate to a parameter table it
// does not include; 9600 8E1 is drivegate's default (README.md). Addresses 1..31, 0 broadcast,
// factory setting 01 (document, "address").
extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    drivegate::kAdapterApiVersion,
    "ed3100",
    "ED3100 variable-frequency drive, Modbus RTU with its 03 reply quirk",
    drivegate::ed3100::kOptionSpecs.data(),
    drivegate::ed3100::kOptionSpecs.size(),
    {9600, drivegate::Parity::even, 8, 1, false},
    0,
    31,
    1,
    false,
    &drivegate::ed3100::create_driver,
    &drivegate::ed3100::create_simulator,
};
