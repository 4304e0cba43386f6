// Impossible hand samples: the rule lives in common/ (tachi/common/hand_speed.hpp) because the simulator
// applies it to stroke CSVs too; the filter uses it under its own names.
#pragma once

#include "tachi/common/hand_speed.hpp"

namespace tachi::filter {

using common::HandSpeedLimit;
using common::OutlierParams;

}  // namespace tachi::filter
