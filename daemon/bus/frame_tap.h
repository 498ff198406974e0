// A frame tap: an observer of one line's traffic, frame by frame, for a capture (/api/v1/capture,
// docs/capture.md). The bus engine calls it with each frame it sends, when it sends it, and with
// each frame it receives, once the station's verdict has said where the frame ends; bytes nobody
// could place (line noise, a stripped echo that did not match) go as their own, flagged, frame.
// An engine with no tap attached does nothing more than test an empty vector.
#pragma once

#include <cstdint>

#include "drivegate/driver.h"

namespace drivegate {

class Station;

enum class FrameDirection : std::uint8_t {
  to_drive = 0,    // gateway -> drive
  from_drive = 1,  // drive -> gateway
};

// What the engine made of a frame (bits; docs/capture.md, "flags").
namespace frame_flags {
inline constexpr std::uint8_t bad_checksum = 0x01;  // the station's verdict: damaged
inline constexpr std::uint8_t noise = 0x02;         // not a frame: bytes nobody could place
inline constexpr std::uint8_t nack = 0x04;          // the device refused the request
inline constexpr std::uint8_t foreign = 0x08;       // a well-formed frame not for us
inline constexpr std::uint8_t echo = 0x10;          // one-wire echo that differed from what we sent
inline constexpr std::uint8_t retry = 0x20;         // a resend of the frame before
}  // namespace frame_flags

struct TappedFrame {
  FrameDirection direction = FrameDirection::to_drive;
  std::uint8_t flags = 0;
  const Station* station = nullptr;  // the device it is from or for; nullptr: nobody's
  ByteView bytes;
};

class FrameTap {
 public:
  virtual ~FrameTap() = default;
  // `at` is the engine's (steady, injected) time; a tap wanting wall-clock time maps it itself.
  // Called on the engine's thread; must not call back into the engine.
  virtual void on_frame(const TappedFrame& frame, TimePoint at) = 0;
};

}  // namespace drivegate
