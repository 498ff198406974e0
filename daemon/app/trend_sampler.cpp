#include "app/trend_sampler.h"

#include <cmath>
#include <limits>

#include "status/status_view.h"

namespace drivegate {

namespace {
constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
}  // namespace

void TrendSampler::sample(const Gateway& gateway, std::int64_t unix_ms, TimePoint now) {
  std::vector<std::string> keys;
  keys.reserve(gateway.devices().size() + gateway.buses().size());
  for (const auto& d : gateway.devices()) {
    const bool known = d->line().health.ever_good() && !d->comm_lost();
    const CommonState& s = d->state();
    series_.assign({{"speed_rpm", "rpm"}, {"setpoint_rpm", "rpm"}});
    values_.assign({known && !s.speed_unknown ? static_cast<float>(s.speed_rpm) : kUnknown,
                    known ? static_cast<float>(s.setpoint_rpm) : kUnknown});
    const auto& values = d->driver().values();
    for (const MappedPoint& p : d->map().points()) {
      if (p.common() || !p.spec.trend) continue;
      series_.push_back({p.spec.name, p.spec.unit});
      const bool held = known && p.index < values.size() &&
                        !std::holds_alternative<std::monostate>(values[p.index]);
      values_.push_back(held ? static_cast<float>(as_double(values[p.index])) : kUnknown);
    }
    keys.push_back("device:" + d->config().name);
    store_.add(keys.back(), series_, unix_ms, values_);
  }
  for (const auto& b : gateway.buses()) {
    const std::string& name = b->config().name;
    const double busy = line_busy_seconds(*b);
    auto [it, fresh] = buses_.try_emplace(name, BusMark{busy, now});
    float percent = kUnknown;
    const double span = std::chrono::duration<double>(now - it->second.at).count();
    if (!fresh && span > 0 && busy >= it->second.busy_seconds) {
      percent =
          static_cast<float>(std::min(100.0, 100.0 * (busy - it->second.busy_seconds) / span));
    }
    it->second = {busy, now};
    series_.assign({{"utilisation", "%"}});
    values_.assign({percent});
    keys.push_back("bus:" + name);
    store_.add(keys.back(), series_, unix_ms, values_);
  }
  store_.keep_only(keys);
  std::erase_if(buses_, [&](const auto& kv) {
    return std::find(keys.begin(), keys.end(), "bus:" + kv.first) == keys.end();
  });
}

}  // namespace drivegate
