// Plugins the loader must refuse (see plugin_test.cpp).
#include "drivegate/adapter.h"

#ifdef BAD_API_VERSION
extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    999,
    "from-the-future",
    "an adapter built for another drivegate",
    nullptr,
    0,
    {9600, drivegate::Parity::none, 8, 1, false},
    0,
    0,
    0,
    false,
    nullptr,
    nullptr};
#else
extern "C" DRIVEGATE_EXPORT const int not_a_drivegate_adapter;
const int not_a_drivegate_adapter = 1;
#endif
