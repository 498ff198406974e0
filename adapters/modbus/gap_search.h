// Finding what a slave refuses inside a block it refused as a whole with exception 02 (illegal
// data address, Application Protocol 7): a register in a gap the block reads through (max_gap),
// or a point the slave lacks. Pure: the driver asks next(), sends it, and says how it was answered.
//
// The block is cut into parts: each point (its registers or bit together: a slave may refuse half
// of a 32-bit value) and each unused register (or bit) between two points. The search halves the
// refused run of parts: the left half is asked; read, it is served and the right half holds what
// was refused (it is not asked whole); refused, the left half is halved again and the right half
// asked whole later. One refused part among n costs at most 2 x ceil(log2 n) + 1 reads, each of
// which that succeeds reads its points. A part is found refused only when asked alone and refused
// twice in a row, and a part that must hold a refusal (asked alone and refused once, or the half
// beside a half that was read) but is read says the slave refuses now and then: the search ends
// at once having found nothing (glitched()), and the plan stays as it was.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "planner.h"
#include "profile.h"

namespace drivegate::modbus_device {

class GapSearch {
 public:
  // A run of registers (or bits) of the block: a point, or one unused register.
  struct Part {
    std::uint16_t start = 0;
    std::uint16_t count = 0;
    std::optional<std::size_t> point;  // index into Profile::points, or nothing for a gap
  };

  // `refused`: a block the slave answered with exception 02.
  GapSearch(const Profile& profile, const Block& refused);

  // The read to ask next; nothing once done().
  [[nodiscard]] std::optional<Block> next() const;
  // next() was answered: refused with exception 02 (true), or read (false).
  void answered(bool refused);
  [[nodiscard]] bool done() const { return todo_.empty(); }
  // The block the search began with.
  [[nodiscard]] const Block& block() const { return block_; }
  // The parts found refused, by address.
  [[nodiscard]] const std::vector<Part>& refused() const { return refused_; }
  // Reads answered so far.
  [[nodiscard]] int asked() const { return asked_; }
  // The search ended on a read that contradicted a refusal before it.
  [[nodiscard]] bool glitched() const { return glitched_; }

 private:
  // unknown: not asked yet. left: the left half of a refused run; when it is read, the right
  // half (below it) holds the refusal. suspect: holds a refused part; asked only alone.
  enum class Kind : std::uint8_t { unknown, left, suspect };
  struct Run {
    std::size_t begin = 0;
    std::size_t end = 0;  // one past the last part
    Kind kind = Kind::unknown;
    int refusals = 0;  // of this run asked alone, in a row
  };
  // Splits the top of the stack until it is a run to ask.
  void settle();

  Block block_;
  std::vector<Part> parts_;
  std::vector<Run> todo_;  // a stack: the back is asked next
  std::vector<Part> refused_;
  int asked_ = 0;
  bool glitched_ = false;
};

}  // namespace drivegate::modbus_device
