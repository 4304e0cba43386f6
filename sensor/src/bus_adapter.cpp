#include "bus_adapter.hpp"

namespace tachi::sensor {

tachi_msg_RawHandSample to_msg(const HandObservation& hand, std::uint32_t sensor_id, std::uint64_t frame,
                               std::int64_t capture_time_ns, std::int64_t acquired_ns) {
  tachi_msg_RawHandSample m{};
  m.sensor_id = sensor_id;
  m.frame = frame;
  m.capture_time_ns = capture_time_ns;
  m.acquired_ns = acquired_ns;
  if (hand.tracked) {
    m.position_m = {hand.position_m.x(), hand.position_m.y(), hand.position_m.z()};
    m.pixel_u = hand.u;
    m.pixel_v = hand.v;
    m.confidence = hand.confidence;
  }
  m.tracked = hand.tracked;
  return m;
}

}  // namespace tachi::sensor
