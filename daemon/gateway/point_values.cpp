#include "gateway/point_values.h"

#include <algorithm>
#include <array>
#include <optional>
#include <span>

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

namespace {

// What a point shows: its registers' value; Value{} where it is unknown (an adapter's point its
// driver does not know, whatever its registers hold; a common row holding its unknown mark; a
// float that is not a number); nothing where the registers cannot be read as its type.
std::optional<Value> value_of(const MappedPoint& p, std::span<const std::uint16_t> regs,
                              const std::vector<Value>& driver_values) {
  if (p.source == PointSource::adapter && p.index < driver_values.size() &&
      std::holds_alternative<std::monostate>(driver_values[p.index])) {
    return Value{};
  }
  if (is_bit_table(p.spec.table)) return Value{std::int64_t{regs[0] != 0 ? 1 : 0}};
  if (p.spec.type == PointType::string) return decode_text(regs);  // a serial number, a name
  auto v = decode_value(p.spec, regs);
  if (!v) {  // a float that is NaN or infinite is unknown; other types always decode
    if (p.spec.type == PointType::f32 || p.spec.type == PointType::f64) return Value{};
    return std::nullopt;
  }
  const CommonRow* row = p.row();
  const auto* i64 = std::get_if<std::int64_t>(&*v);
  if (row != nullptr && row->unknown && i64 != nullptr && *i64 == *row->unknown) return Value{};
  return v;
}

}  // namespace

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
    const std::size_t count = p.spec.address_count();
    if (std::size_t{p.address} + count > image[i].size() || !readable[i][p.address]) continue;
    if (auto v = value_of(p, std::span(image[i]).subspan(p.address, count), values)) {
      out.emplace_back(&p, std::move(*v));
    }
  }
}

std::vector<PointValue> point_values(Device& device) {
  std::vector<PointValue> out;
  point_values(device, Clock::now(), out);
  return out;
}

}  // namespace drivegate
