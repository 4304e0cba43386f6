// The cutting gate: when does the hand cut? An explicit state machine (docs/filter.md has the table).
// Seed 000 section 3.1 starts cutting when the hand-to-cloth distance falls below a threshold and stops
// it when the distance rises above it; section 5 reports that the hand fluctuates at the start and end
// of a cut and proposes voice start/stop. Here the threshold has hysteresis (enter < exit) and a dwell
// (a condition must hold for some samples), and voice commands can open and close the gate.
#pragma once

#include "tachi/filter/types.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace tachi::filter {

/// Which sources may open and close the gate.
enum class GateMode : std::uint8_t {
  Threshold,  ///< hand-to-cloth distance only; voice commands are ignored
  Voice,      ///< voice commands only; distance is ignored
  Either,     ///< both: a voice-opened stroke closes only by voice; a voice stop also ends a threshold stroke
};

std::optional<GateMode> gate_mode_from_string(const std::string& name);
std::string to_string(GateMode mode);

/// The gate's states. Arming and Disarming are the dwell states of the threshold.
enum class GatePhase : std::uint8_t {
  Idle,                ///< not cutting
  Arming,              ///< hand came within the enter distance; waiting out the enter dwell
  CuttingByThreshold,  ///< cutting, opened by the threshold
  Disarming,           ///< still cutting; hand beyond the exit distance or lost, waiting out the exit dwell
  CuttingByVoice,      ///< cutting, opened by a voice command: only a voice command closes it
  HeldOff,             ///< not cutting after a voice stop (Either mode): the threshold may not reopen
                       ///< until the hand has gone beyond the exit distance
};
inline constexpr int kGatePhaseCount = 6;

/// Whatever can happen between two samples.
enum class GateEvent : std::uint8_t {
  Near,          ///< distance < enter distance (or the hand is behind the cloth)
  Between,       ///< enter <= distance <= exit: the hysteresis band
  Far,           ///< distance > exit distance
  Lost,          ///< the sensor lost the hand
  VoiceStart,
  VoiceStop,
  DwellElapsed,  ///< the current dwell state has lasted its dwell
};
inline constexpr int kGateEventCount = 7;

std::string to_string(GatePhase phase);
std::string to_string(GateEvent event);

/// True for the phases in which the gate is open (the hand cuts).
bool is_cutting(GatePhase phase);

/// The transition function: the whole behaviour of the gate, tested as a table.
/// The mode filters events (Threshold ignores voice events, Voice ignores distance and dwell events);
/// everything else is the Either table.
GatePhase next_phase(GateMode mode, GatePhase phase, GateEvent event);

struct GateParams {
  GateMode mode = GateMode::Threshold;
  float enter_distance_m = 0.05F;  ///< start cutting below this hand-to-cloth distance
  float exit_distance_m = 0.08F;   ///< stop cutting above this (> enter: hysteresis)
  int enter_dwell_samples = 2;     ///< samples within reach before the gate opens (>= 1)
  int exit_dwell_samples = 4;      ///< samples out of reach (or lost) before the gate closes (>= 1)
  /// A threshold stroke holds (stays open without cutting) while the hand moves toward or away from
  /// the cloth faster than this, m/s along the cloth's normal; 0 disables. Cutting is a motion along
  /// the cloth; reaching in and pulling out are what made the seed's cuts stray (seed 000 sec. 5).
  float max_normal_speed_mps = 0.25F;
};

std::optional<std::string> validate(const GateParams& params);

/// Classifies a distance into Near/Between/Far for the thresholds.
GateEvent classify_distance(const GateParams& params, float distance_m);

/// What the gate says after a sample.
struct GateStatus {
  GatePhase phase = GatePhase::Idle;
  GateOutput output = GateOutput::Idle;
  std::uint32_t stroke_id = 0;
  GateSource opened_by = GateSource::None;
  GateSource closed_by = GateSource::None;
};

/// The gate with its memory: the phase, the dwell counter and the stroke bookkeeping.
class Gate {
 public:
  explicit Gate(const GateParams& params) : params_(params) {}

  /// Applies a voice command now (it arrived before the next hand sample). Grab and Release work in
  /// every mode and beside the phases: while grabbing the output is Grabbing and distance events are
  /// ignored (the hand is at the cloth on purpose); a release holds the threshold off until the hand has
  /// gone beyond the exit distance, so letting go does not start a cut. Start while grabbing releases
  /// first. A grab while the gate is cutting is refused (one hand, one tool): returns why.
  std::optional<std::string> on_voice(VoiceCommandKind command);
  /// Applies one hand sample: its distance event (nullopt distance = hand lost), then the dwell.
  const GateStatus& on_sample(std::optional<float> distance_m);

  const GateStatus& status() const noexcept { return status_; }
  bool grabbing() const noexcept { return grabbing_; }
  const GateParams& params() const noexcept { return params_; }

 private:
  void apply(GateEvent event);

  GateParams params_;
  void release_grab();

  GateStatus status_;
  int dwell_ = 0;
  bool grabbing_ = false;
};

}  // namespace tachi::filter
