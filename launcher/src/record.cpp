#include "record.hpp"

#include "tachi/common/process.hpp"
#include "tachi/common/latency.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <set>

namespace tachi::launcher {
namespace {
using Clock = std::chrono::steady_clock;

std::vector<const bus::TopicInfo*> selected(const std::vector<std::string>& names) {
  std::vector<const bus::TopicInfo*> topics;
  for (const auto& t : bus::all_topics())
    if (names.empty() || std::find(names.begin(), names.end(), t.name) != names.end()) topics.push_back(&t);
  return topics;
}

const char* profile_name(bus::QosProfile p) {
  switch (p) {
    case bus::QosProfile::SensorData: return "SensorData";
    case bus::QosProfile::Commands: return "Commands";
    case bus::QosProfile::Strokes: return "Strokes";
    case bus::QosProfile::Topology: return "Topology";
    case bus::QosProfile::State: return "State";
    case bus::QosProfile::Status: return "Status";
  }
  return "?";
}

}  // namespace

std::vector<std::string> unknown_topics(const std::vector<std::string>& topics) {
  std::vector<std::string> unknown;
  for (const auto& t : topics)
    if (bus::find_topic(t) == nullptr) unknown.push_back(t);
  return unknown;
}

Recorder::Recorder(const bus::Participant& participant, const RecordOptions& options)
    : options_(options), waitset_(participant), writer_(options.file, "", "tachi record"), started_(Clock::now()) {
  std::map<std::string, std::uint16_t> schema_ids;
  for (const auto* topic : selected(options.topics)) {
    const std::string type(topic->type_name());
    if (!schema_ids.contains(type)) schema_ids[type] = writer_.add_schema(type, "omgidl", bus::kTachiIdl);
    channels_.push_back(writer_.add_channel(schema_ids[type], topic->name, "cdr", {{"qos_profile", profile_name(topic->profile)}}));
    sequences_.push_back(0);
    readers_.push_back(std::make_unique<bus::SerializedReader>(participant, *topic, bus::ReaderRole::Recorder));
    waitset_.attach(*readers_.back());
    result_.messages[topic->name] = 0;
  }
  if (options.foxglove) {
    scene_.emplace();
    std::uint16_t* ids[] = {&fox_cloth_, &fox_hand_, &fox_latency_};
    for (std::size_t i = 0; i < foxglove_channels().size(); ++i) {
      const auto& c = foxglove_channels()[i];
      *ids[i] = writer_.add_channel(writer_.add_schema(c.schema_name, "jsonschema", c.schema), c.topic, "json");
      result_.messages[c.topic] = 0;
    }
  }
}

void Recorder::write_json(std::uint16_t channel, const nlohmann::json& message, std::uint64_t now_ns) {
  const std::string text = message.dump();
  if (full_ || (options_.max_bytes > 0 && writer_.closed_size_with(channel, text.size()) > options_.max_bytes)) {
    full_ = true;
    result_.ended = "--max-bytes reached";
    return;
  }
  writer_.write({channel, fox_sequence_++, now_ns, now_ns, {reinterpret_cast<const std::byte*>(text.data()), text.size()}});
  ++result_.messages[foxglove_channels()[channel == fox_cloth_ ? 0 : channel == fox_hand_ ? 1 : 2].topic];
  ++result_.total;
}

// The derived Foxglove channels, from the samples as they are recorded (--foxglove only: this
// deserializes what the plain recorder stores untouched).
void Recorder::derive(const bus::TopicInfo& topic, std::span<const std::byte> cdr, std::uint64_t now_ns) {
  namespace t = bus::topics;
  const std::string_view name = topic.name;
  if (name == t::cloth_topology.name) {
    scene_->on_topology(*bus::deserialize<tachi_msg_ClothTopology>(cdr, scratch_));
  } else if (name == t::cloth_topology_delta.name) {
    scene_->on_topology_delta(*bus::deserialize<tachi_msg_ClothTopologyDelta>(cdr, scratch_));
  } else if (name == t::node_status.name) {
    scene_->on_status(*bus::deserialize<tachi_msg_NodeStatus>(cdr, scratch_));
  } else if (name == t::stroke.name) {
    write_json(fox_hand_, scene_->on_stroke(*bus::deserialize<tachi_msg_StrokeSample>(cdr, scratch_), now_ns), now_ns);
  } else if (name == t::cloth_state.name) {
    if (const auto frame = scene_->on_state(*bus::deserialize<tachi_msg_ClothState>(cdr, scratch_), now_ns)) {
      write_json(fox_cloth_, frame->cloth, now_ns);
      write_json(fox_latency_, frame->latency, now_ns);
    }
  }
}

bool Recorder::poll(std::chrono::milliseconds timeout) {
  if (full_) return false;
  waitset_.wait(timeout);
  const auto now_ns = static_cast<std::uint64_t>(common::wall_clock_ns());
  for (std::size_t i = 0; i < readers_.size() && !full_; ++i) {
    readers_[i]->take([&](std::span<const std::byte> cdr, std::int64_t source_ns) {
      if (full_) return;  // taken after the size limit: not stored, and not counted as stored
      if (options_.max_bytes > 0 && writer_.closed_size_with(channels_[i], cdr.size()) > options_.max_bytes) {
        full_ = true;
        result_.ended = "--max-bytes reached";
        return;
      }
      writer_.write({channels_[i], sequences_[i]++, now_ns, static_cast<std::uint64_t>(std::max<std::int64_t>(source_ns, 0)), cdr});
      ++result_.messages[readers_[i]->topic().name];
      ++result_.total;
      if (scene_) {
        try {
          derive(readers_[i]->topic(), cdr, now_ns);
        } catch (const std::invalid_argument& e) {
          spdlog::warn("--foxglove: {}", e.what());
        }
      }
    });
  }
  if (!full_ && options_.duration_s > 0 && Clock::now() - started_ >= std::chrono::duration<double>(options_.duration_s)) {
    full_ = true;
    result_.ended = "--duration reached";
  }
  return !full_;
}

RecordResult Recorder::finish(const std::string& ended) {
  if (!full_) poll(std::chrono::milliseconds(0));
  for (auto& r : readers_) result_.lost += r->lost();
  writer_.close();
  result_.bytes = writer_.bytes();
  if (result_.ended.empty()) result_.ended = ended;
  return result_;
}

BackgroundRecorder::BackgroundRecorder(const bus::Participant& participant, const RecordOptions& options)
    : recorder_(participant, options), thread_([this] {
        // A failure (a full disk) ends the recording, not the run it records.
        try {
          while (!stop_ && recorder_.poll(std::chrono::milliseconds(50))) {
          }
        } catch (const std::exception& e) {
          error_ = e.what();
          spdlog::error("recording stopped: {}", e.what());
        }
      }) {}

BackgroundRecorder::~BackgroundRecorder() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

RecordResult BackgroundRecorder::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  auto result = recorder_.finish("stopped");
  if (!error_.empty()) result.ended = "failed: " + error_;
  return result;
}

PlayResult play(const bus::Participant& participant, const PlayOptions& options) {
  PlayResult result;
  // First pass: the channels, so every writer exists (and has its readers) before the first message.
  std::map<std::uint16_t, mcap::Schema> schemas;
  std::map<std::uint16_t, std::unique_ptr<bus::SerializedWriter>> writers;
  std::set<std::string> warned;
  mcap::ReadCallbacks first;
  first.schema = [&](const mcap::Schema& s) { schemas[s.id] = s; };
  first.channel = [&](const mcap::Channel& c) {
    if (writers.contains(c.id)) return;
    const bus::TopicInfo* topic = bus::find_topic(c.topic);
    const bool wanted = options.topics.empty() || std::find(options.topics.begin(), options.topics.end(), c.topic) != options.topics.end();
    const auto schema = schemas.find(c.schema_id);
    if (!wanted) {
      writers[c.id] = nullptr;
    } else if (topic == nullptr || c.message_encoding != "cdr" || schema == schemas.end() || schema->second.name != topic->type_name()) {
      if (warned.insert(c.topic).second)
        spdlog::warn("{}: channel {} ({} {}) is not a tachi topic of this build; not played", options.file.string(), c.topic,
                     schema == schemas.end() ? "no schema" : schema->second.name, c.message_encoding);
      writers[c.id] = nullptr;
    } else {
      writers[c.id] = std::make_unique<bus::SerializedWriter>(participant, *topic);
      result.published[c.topic] = 0;
    }
  };
  mcap::read(options.file, first);
  if (result.published.empty()) throw std::runtime_error(options.file.string() + ": no tachi topic to play");
  if (options.wait_s > 0) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(options.wait_s);
    for (const auto& [id, w] : writers)
      if (w && !w->wait_for_readers(1, std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - Clock::now())))
        spdlog::warn("no reader of {} after {} s; playing anyway", w->topic().name, options.wait_s);
  }

  do {
    std::optional<std::uint64_t> file_start, first_played;
    const auto wall_start = Clock::now();
    mcap::ReadCallbacks callbacks;
    callbacks.message = [&](const mcap::Message& m) {
      if (common::stop_requested()) return false;
      if (!file_start) file_start = m.log_time;
      const auto it = writers.find(m.channel_id);
      if (it == writers.end() || !it->second) {
        ++result.skipped;
        return true;
      }
      if (m.log_time < *file_start + static_cast<std::uint64_t>(options.start_s * 1e9)) return true;
      if (!first_played) first_played = m.log_time;
      const auto due = wall_start + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double, std::nano>(static_cast<double>(m.log_time - *first_played) / options.rate));
      if (!common::sleep_unless_stopped(due)) return false;
      try {
        it->second->write(m.data);
        ++result.published[it->second->topic().name];
      } catch (const std::invalid_argument& e) {
        ++result.skipped;
        spdlog::warn("{}: message {} on {}: {}", options.file.string(), m.sequence, it->second->topic().name, e.what());
      }
      return true;
    };
    mcap::read(options.file, callbacks);
  } while (options.loop && !common::stop_requested());
  // Reliable readers get the last samples before the writers go.
  for (const auto& [id, w] : writers)
    if (w) w->wait_for_acks(std::chrono::seconds(2));
  return result;
}

}  // namespace tachi::launcher
