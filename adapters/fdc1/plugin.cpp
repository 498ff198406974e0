// The fdc1 plugin descriptor.
#include "drivegate/adapter.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace {

std::unique_ptr<drivegate::Driver> create_driver(const drivegate::DeviceEnv& env,
                                                 std::string& error) {
  return drivegate::fdc1::make_driver(env, error);
}

std::unique_ptr<drivegate::Simulator> create_simulator(const drivegate::SimEnv& env,
                                                       std::string& error) {
  return drivegate::fdc1::make_simulator(env, error);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const drivegate::AdapterDescriptor drivegate_adapter = {
    drivegate::kAdapterApiVersion,
    "fdc1",
    "FDC1 12-42 V DC compressor controller, protocol v2 (streaming)",
    drivegate::fdc1::kOptionSchema.data(),
    drivegate::fdc1::kOptionSchema.size(),
    // HARDWARE: "1200 baud 1 start bit ... 8 bits of data ... no parity 1 stop bit"; TTL UART
    // with separate RxD / TxD: no echo.
    {1200, drivegate::Parity::none, 8, 1, false},
    0,  // the protocol has no address
    0,
    0,
    true,  // OUTPUT: transmits every 0.5 s unasked
    create_driver,
    create_simulator,
};
