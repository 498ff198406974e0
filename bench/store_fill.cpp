// dg-store-fill STATE_DIR GROUP EDGE DEVICE COUNT: COUNT changes of DEVICE's speed_rpm kept in the
// store and forward of edge node GROUP/EDGE under STATE_DIR, as an outage would have kept them
// (daemon/mqtt/store_forward.h): the backlog bench/replay_cost.sh has drivegated replay.
#include <spdlog/logger.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <string>

#include "mqtt/bd_seq_file.h"
#include "mqtt/store_forward.h"

int main(int argc, char** argv) {
  using namespace drivegate;
  if (argc != 6) {
    std::cerr << "usage: dg-store-fill STATE_DIR GROUP EDGE DEVICE COUNT\n";
    return 2;
  }
  const auto dir = mqtt::edge_node_state_path(argv[1], argv[2], argv[3], ".store");
  const long count = std::atol(argv[5]);
  mqtt::SpoolLimits limits;
  limits.max_bytes = 1ULL << 30;  // all of them: the bench's daemon says its own limit
  mqtt::StoreForward store(dir, limits, 500, std::make_shared<spdlog::logger>("dg-store-fill"));
  if (!store.open()) return 1;
  const auto now =
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count());
  for (long i = 0; i < count; ++i) {
    const std::uint64_t at = now - static_cast<std::uint64_t>(count - i);
    sparkplug::Payload p;
    p.timestamp = at;
    p.metrics.push_back({"speed_rpm",
                         sparkplug::DataType::int16,
                         sparkplug::MetricValue{std::int64_t{i % 1000}},
                         {},
                         at,
                         true});
    store.keep(argv[4], p, at);
  }
  store.sync();
  std::cout << dir.string() << "\n";
  return 0;
}
