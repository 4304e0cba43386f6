// The filter's workspace mapping is the shared one (tachi/common/workspace.hpp): the simulator places a
// recording's scene with the same type.
#pragma once

#include "tachi/common/workspace.hpp"

namespace tachi::filter {

using common::default_mapping;
using common::validate;
using common::WorkspaceMapping;

}  // namespace tachi::filter
