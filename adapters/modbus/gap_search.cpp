#include "gap_search.h"

#include <algorithm>

namespace drivegate::modbus_device {
namespace {

// A part is refused when asked alone and refused this many times in a row.
constexpr int kRefusalsOfAPart = 2;

}  // namespace

GapSearch::GapSearch(const Profile& profile, const Block& refused) : block_(refused) {
  std::vector<std::size_t> points = refused.points;
  std::sort(points.begin(), points.end(), [&](std::size_t a, std::size_t b) {
    return profile.points[a].address < profile.points[b].address;
  });
  std::uint32_t next = refused.start;
  for (const std::size_t i : points) {
    const ProfilePoint& p = profile.points[i];
    for (std::uint32_t a = next; a < p.address; ++a) {
      parts_.push_back({static_cast<std::uint16_t>(a), 1, std::nullopt});
    }
    parts_.push_back({p.address, p.width(), i});
    next = std::max<std::uint32_t>(next, std::uint32_t{p.address} + p.width());
  }
  // The block was refused whole: it holds a refusal, known from one read (of all of it).
  todo_.push_back({0, parts_.size(), Kind::suspect, parts_.size() == 1 ? 1 : 0});
  settle();
}

std::optional<Block> GapSearch::next() const {
  if (todo_.empty()) return std::nullopt;
  const Run& r = todo_.back();
  Block b;
  b.table = block_.table;
  b.start = parts_[r.begin].start;
  const Part& last = parts_[r.end - 1];
  b.count = static_cast<std::uint16_t>(last.start + last.count - b.start);
  for (std::size_t i = r.begin; i < r.end; ++i) {
    if (parts_[i].point) b.points.push_back(*parts_[i].point);
  }
  return b;
}

void GapSearch::answered(bool refused) {
  if (todo_.empty()) return;
  ++asked_;
  Run& r = todo_.back();
  if (!refused && r.kind == Kind::suspect) {
    // A part that held a refusal is read: the slave refuses now and then, it lacks nothing
    // this search can tell. It ends, having found nothing.
    todo_.clear();
    refused_.clear();
    glitched_ = true;
    return;
  }
  if (!refused) {
    const Kind kind = r.kind;
    todo_.pop_back();
    // The left half was read: what the run held is in the right half, below it.
    if (kind == Kind::left && !todo_.empty()) todo_.back().kind = Kind::suspect;
  } else {
    r.kind = Kind::suspect;
    if (r.end - r.begin == 1) ++r.refusals;
  }
  settle();
}

void GapSearch::settle() {
  while (!todo_.empty()) {
    Run r = todo_.back();
    if (r.kind != Kind::suspect) return;
    if (r.end - r.begin > 1) {
      todo_.pop_back();
      const std::size_t mid = r.begin + (r.end - r.begin) / 2;
      todo_.push_back({mid, r.end, Kind::unknown, 0});
      todo_.push_back({r.begin, mid, Kind::left, 0});
      return;
    }
    if (r.refusals < kRefusalsOfAPart) return;
    refused_.push_back(parts_[r.begin]);
    todo_.pop_back();
  }
}

}  // namespace drivegate::modbus_device
