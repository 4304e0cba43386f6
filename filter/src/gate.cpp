#include "tachi/filter/gate.hpp"

#include <cmath>

namespace tachi::filter {

std::optional<GateMode> gate_mode_from_string(const std::string& name) {
  if (name == "threshold") return GateMode::Threshold;
  if (name == "voice") return GateMode::Voice;
  if (name == "either") return GateMode::Either;
  return std::nullopt;
}

std::string to_string(GateMode mode) {
  switch (mode) {
    case GateMode::Threshold: return "threshold";
    case GateMode::Voice: return "voice";
    case GateMode::Either: return "either";
  }
  return "?";
}

std::string to_string(GatePhase phase) {
  switch (phase) {
    case GatePhase::Idle: return "Idle";
    case GatePhase::Arming: return "Arming";
    case GatePhase::CuttingByThreshold: return "CuttingByThreshold";
    case GatePhase::Disarming: return "Disarming";
    case GatePhase::CuttingByVoice: return "CuttingByVoice";
    case GatePhase::HeldOff: return "HeldOff";
  }
  return "?";
}

std::string to_string(GateEvent event) {
  switch (event) {
    case GateEvent::Near: return "Near";
    case GateEvent::Between: return "Between";
    case GateEvent::Far: return "Far";
    case GateEvent::Lost: return "Lost";
    case GateEvent::VoiceStart: return "VoiceStart";
    case GateEvent::VoiceStop: return "VoiceStop";
    case GateEvent::DwellElapsed: return "DwellElapsed";
  }
  return "?";
}

bool is_cutting(GatePhase phase) {
  return phase == GatePhase::CuttingByThreshold || phase == GatePhase::Disarming || phase == GatePhase::CuttingByVoice;
}

namespace {
bool is_voice(GateEvent e) { return e == GateEvent::VoiceStart || e == GateEvent::VoiceStop; }
}  // namespace

GatePhase next_phase(GateMode mode, GatePhase phase, GateEvent event) {
  using P = GatePhase;
  using E = GateEvent;
  if (mode == GateMode::Threshold && is_voice(event)) return phase;
  if (mode == GateMode::Voice && !is_voice(event)) return phase;
  // After a voice stop the threshold must not reopen at once with the hand still at the cloth;
  // with voice alone there is no threshold to hold off.
  const P after_voice_stop = mode == GateMode::Either ? P::HeldOff : P::Idle;
  switch (phase) {
    case P::Idle:
      if (event == E::Near) return P::Arming;
      if (event == E::VoiceStart) return P::CuttingByVoice;
      return P::Idle;
    case P::Arming:
      if (event == E::Far || event == E::Lost) return P::Idle;
      if (event == E::DwellElapsed) return P::CuttingByThreshold;
      if (event == E::VoiceStart) return P::CuttingByVoice;
      if (event == E::VoiceStop) return after_voice_stop;
      return P::Arming;  // Near, Between: the hysteresis band keeps the dwell going
    case P::CuttingByThreshold:
      if (event == E::Far || event == E::Lost) return P::Disarming;
      if (event == E::VoiceStop) return after_voice_stop;
      return P::CuttingByThreshold;
    case P::Disarming:
      if (event == E::Near || event == E::Between) return P::CuttingByThreshold;  // a fluctuation, same stroke
      if (event == E::DwellElapsed) return P::Idle;
      if (event == E::VoiceStop) return after_voice_stop;
      return P::Disarming;  // Far, Lost, VoiceStart (already cutting)
    case P::CuttingByVoice:
      if (event == E::VoiceStop) return after_voice_stop;
      return P::CuttingByVoice;
    case P::HeldOff:
      if (event == E::Far || event == E::Lost) return P::Idle;
      if (event == E::VoiceStart) return P::CuttingByVoice;
      return P::HeldOff;
  }
  return phase;
}

std::optional<std::string> validate(const GateParams& p) {
  if (!std::isfinite(p.enter_distance_m) || p.enter_distance_m <= 0.0F || p.enter_distance_m > 10.0F)
    return "gate.enter_distance_m must be in (0, 10] m";
  if (!std::isfinite(p.exit_distance_m) || p.exit_distance_m <= p.enter_distance_m || p.exit_distance_m > 10.0F)
    return "gate.exit_distance_m must be in (enter_distance_m, 10] m (hysteresis needs exit > enter)";
  if (p.enter_dwell_samples < 1 || p.enter_dwell_samples > 300) return "gate.enter_dwell_samples must be in [1, 300]";
  if (p.exit_dwell_samples < 1 || p.exit_dwell_samples > 300) return "gate.exit_dwell_samples must be in [1, 300]";
  if (!std::isfinite(p.max_normal_speed_mps) || p.max_normal_speed_mps < 0.0F || p.max_normal_speed_mps > 100.0F)
    return "gate.max_normal_speed_mps must be in [0, 100] m/s (0 disables)";
  return std::nullopt;
}

GateEvent classify_distance(const GateParams& params, float distance_m) {
  if (distance_m < params.enter_distance_m) return GateEvent::Near;
  if (distance_m > params.exit_distance_m) return GateEvent::Far;
  return GateEvent::Between;
}

void Gate::apply(GateEvent event) {
  const GatePhase before = status_.phase;
  const GatePhase after = next_phase(params_.mode, before, event);
  if (after == before) return;
  if (after == GatePhase::Arming || after == GatePhase::Disarming) dwell_ = 0;
  if (!is_cutting(before) && is_cutting(after)) {
    ++status_.stroke_id;
    status_.opened_by = after == GatePhase::CuttingByVoice ? GateSource::Voice : GateSource::Threshold;
    status_.closed_by = GateSource::None;
  } else if (is_cutting(before) && !is_cutting(after)) {
    status_.closed_by = event == GateEvent::VoiceStop ? GateSource::Voice : GateSource::Threshold;
  }
  status_.phase = after;
  status_.output = after == GatePhase::Disarming ? GateOutput::Holding
                   : is_cutting(after)             ? GateOutput::Cutting
                                                   : GateOutput::Idle;
}

void Gate::release_grab() {
  if (!grabbing_) return;
  grabbing_ = false;
  // The hand is at the cloth it just let go of: the threshold may not open a cut there.
  status_.phase = params_.mode == GateMode::Voice ? GatePhase::Idle : GatePhase::HeldOff;
  status_.output = GateOutput::Idle;
}

std::optional<std::string> Gate::on_voice(VoiceCommandKind command) {
  switch (command) {
    case VoiceCommandKind::Grab:
      if (is_cutting(status_.phase))
        return "grab refused: stroke " + std::to_string(status_.stroke_id) + " is cutting (one hand, one tool)";
      grabbing_ = true;
      status_.phase = GatePhase::Idle;  // an arming threshold is abandoned
      status_.output = GateOutput::Grabbing;
      return std::nullopt;
    case VoiceCommandKind::Release:
      release_grab();
      return std::nullopt;
    case VoiceCommandKind::Start:
      release_grab();
      apply(GateEvent::VoiceStart);
      return std::nullopt;
    case VoiceCommandKind::Stop:
      apply(GateEvent::VoiceStop);
      return std::nullopt;
  }
  return std::nullopt;
}

const GateStatus& Gate::on_sample(std::optional<float> distance_m) {
  if (grabbing_) return status_;
  apply(distance_m ? classify_distance(params_, *distance_m) : GateEvent::Lost);
  const GatePhase phase = status_.phase;
  if (phase == GatePhase::Arming || phase == GatePhase::Disarming) {
    ++dwell_;
    const int needed = phase == GatePhase::Arming ? params_.enter_dwell_samples : params_.exit_dwell_samples;
    if (dwell_ >= needed) apply(GateEvent::DwellElapsed);
  }
  return status_;
}

}  // namespace tachi::filter
