// The offline formats: the sensor's hand CSV in (frame,stamp_ns,x,y,z,u,v,tracked,confidence) and the
// stroke CSV out (frame,stamp_ns,x,y,z,gate,stroke_id; gate 0 = idle, 1 = cutting, 2 = holding, 3 = grabbing).
#pragma once

#include "tachi/filter/types.hpp"

#include <istream>
#include <ostream>
#include <string>
#include <vector>

namespace tachi::filter {

struct HandCsv {
  std::vector<HandSample> samples;
  std::vector<std::string> skipped;  ///< one message per unusable row ("line 12: ...")
};

/// Reads the sensor's CSV. Columns are found by header name (order free; extra columns ignored).
/// Throws std::runtime_error when the header lacks a required column; skips (and reports) bad rows.
HandCsv read_hand_csv(std::istream& in);

void write_stroke_csv_header(std::ostream& out);
/// `camera_frame`: write the smoothed camera-frame position instead of the world-frame one.
/// Untracked samples are written with x, y, z = nan.
void write_stroke_csv_row(std::ostream& out, const StrokeSample& sample, bool camera_frame);

}  // namespace tachi::filter
