#include "settings.h"

namespace drivegate::fdc1 {
namespace {

template <class T, class Get>
T get_or(const Options& o, const char* name, T fallback, Get get) {
  return o.has(name) ? static_cast<T>(get(name)) : fallback;
}

}  // namespace

Settings read_settings(const Options& o) {
  Settings s;
  const auto integer = [&](const char* n) { return o.integer(n); };
  const auto boolean = [&](const char* n) { return o.boolean(n); };
  s.slave_mode = get_or(o, "slave_mode", s.slave_mode, boolean);
  s.refresh = std::chrono::seconds(get_or(o, "refresh_s", s.refresh.count(), integer));
  s.confirm = std::chrono::milliseconds(get_or(o, "confirm_ms", s.confirm.count(), integer));
  s.stale = std::chrono::milliseconds(get_or(o, "stale_ms", s.stale.count(), integer));
  s.tolerance_rpm = get_or(o, "tolerance_rpm", s.tolerance_rpm, integer);
  s.allow_nv_programming = get_or(o, "allow_nv_programming", s.allow_nv_programming, boolean);
  return s;
}

}  // namespace drivegate::fdc1
