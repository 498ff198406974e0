#include "gateway/point_values.h"

#include <algorithm>
#include <array>

#include "gateway/value_codec.h"

namespace drivegate {

std::string_view label_of(const PointSpec& spec, const Value& value) {
  if (spec.bit_labels || spec.labels.empty()) return {};
  const auto* i = std::get_if<std::int64_t>(&value);
  if (i == nullptr) return {};
  const auto it = std::find_if(spec.labels.begin(), spec.labels.end(),
                               [&](const Label& l) { return l.value == *i; });
  return it != spec.labels.end() ? std::string_view(it->name) : std::string_view();
}

void point_values(Device& device, TimePoint now, std::vector<PointValue>& out) {
  static const Session kReader{AccessLevel::read, WordOrder::big};
  static constexpr std::array kTables{Table::coil, Table::discrete, Table::input, Table::holding};
  out.clear();
  const RegisterMap& map = device.map();
  // Each table whole, a mapped run per read (a read of a range with a hole in it is refused):
  // the common block's inputs and status bits are computed once per table read, not per point.
  std::array<std::vector<std::uint16_t>, 4> image;
  std::array<std::vector<bool>, 4> readable;
  for (const Table t : kTables) {
    const auto i = static_cast<std::size_t>(t);
    const std::uint16_t size = map.size(t);
    image[i].assign(size, 0);
    readable[i].assign(size, false);
    for (std::size_t a = 0; a < size;) {
      const std::size_t n =
          std::min<std::size_t>(map.mapped_from(t, static_cast<std::uint16_t>(a)), size - a);
      if (n == 0) {
        ++a;
        continue;
      }
      const std::span<std::uint16_t> regs = std::span(image[i]).subspan(a, n);
      if (device.read(kReader, t, static_cast<std::uint16_t>(a), regs, now) == Outcome::ok) {
        std::fill_n(readable[i].begin() + static_cast<std::ptrdiff_t>(a), n, true);
      }
      a += n;
    }
  }
  out.reserve(map.points().size());
  const std::vector<Value>& values = device.driver().values();
  for (const MappedPoint& p : map.points()) {
    const auto i = static_cast<std::size_t>(p.spec.table);
    const bool bits = p.spec.table == Table::coil || p.spec.table == Table::discrete;
    const std::size_t count = bits ? 1 : p.spec.register_count();
    if (std::size_t{p.address} + count > image[i].size() || !readable[i][p.address]) continue;
    const std::span<const std::uint16_t> regs = std::span(image[i]).subspan(p.address, count);
    // What the registers cannot say: an adapter's point its driver does not know, a common row
    // holding its unknown mark, a float that is not a number.
    const bool unknown_to_driver = p.source == PointSource::adapter && p.index < values.size() &&
                                   std::holds_alternative<std::monostate>(values[p.index]);
    if (unknown_to_driver) {
      out.emplace_back(&p, Value{});
    } else if (bits) {
      out.emplace_back(&p, std::int64_t{regs[0] != 0 ? 1 : 0});
    } else if (p.spec.type == PointType::string) {
      out.emplace_back(&p, decode_text(regs));  // a serial number, a drive's name
    } else if (auto v = decode_value(p.spec, regs)) {
      const CommonRow* row = p.row();
      const auto* i64 = std::get_if<std::int64_t>(&*v);
      const bool marked = row != nullptr && row->unknown && i64 != nullptr && *i64 == *row->unknown;
      out.emplace_back(&p, marked ? Value{} : std::move(*v));
    } else if (p.spec.type == PointType::f32 || p.spec.type == PointType::f64) {
      out.emplace_back(&p, Value{});  // NaN or infinite
    }
  }
}

std::vector<PointValue> point_values(Device& device) {
  std::vector<PointValue> out;
  point_values(device, Clock::now(), out);
  return out;
}

}  // namespace drivegate
