#include "go_feap/planning/layer_manager.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>

namespace go_feap::planning {

common::Status LayerManagerConfig::validate() const {
  auto bad = [](const std::string& key, const std::string& why) {
    return common::Status::Error("layers: " + key + " " + why);
  };
  // At least half a metre: a band thinner than the viewpoints' clearance holds no viewpoint, and 1e-12 m
  // overflowed the band count.
  if (!(layer_height >= 0.5) || !std::isfinite(layer_height)) return bad("layer_height", "must be finite and >= 0.5 m");
  if (!(settle_time >= 0.0) || !std::isfinite(settle_time)) return bad("settle_time", "must be finite and >= 0");
  if (max_retries < 1) return bad("max_retries", "must be >= 1");
  // .inf is the way to say "no limit" (a real flight ended by its pilot); NaN, 0 and below are refused.
  if (!(time_limit > 0.0)) return bad("time_limit", "must be > 0 s (.inf for none)");
  if (!(stuck_timeout > 0.0)) return bad("stuck_timeout", "must be > 0 s (.inf for none)");
  if (!(progress_travel >= 0.0) || !std::isfinite(progress_travel)) return bad("progress_travel", "must be finite and >= 0");
  return common::Status::Ok();
}

const char* toString(ExplorationState s) {
  switch (s) {
    case ExplorationState::kWaitTrigger: return "WAIT_TRIGGER";
    case ExplorationState::kExplore: return "EXPLORE";
    case ExplorationState::kFinalPass: return "FINAL_PASS";
    case ExplorationState::kFinished: return "FINISHED";
  }
  return "?";
}

const char* toString(FinishReason r) {
  switch (r) {
    case FinishReason::kNone: return "";
    case FinishReason::kComplete: return "complete";
    case FinishReason::kTimeLimit: return "time_limit";
    case FinishReason::kStuck: return "stuck";
    case FinishReason::kAborted: return "aborted";
  }
  return "?";
}

LayerManager::LayerManager(const LayerManagerConfig& config, const common::Aabb& box, double start_z)
    : config_(config), box_(box) {
  // Equal bands of at most layer_height: a remainder band (0.1 m on a 6.6 m box at 3.25 m) was thinner than
  // the viewpoints' clearance, held no viewpoint, and its frontiers were blacklisted unexplored.
  const double height = box.max.z() - box.min.z();
  count_ = static_cast<int>(std::clamp(std::ceil(height / config.layer_height - 1e-9), 1.0, 1e6));
  band_height_ = height / count_;
  // Clamped as a double first: a start far outside the box (1e300 m, or NaN, from odometry gone wrong) would
  // not fit an int, and the cast would be undefined. A NaN start takes the lowest band.
  const double band_of_start = std::floor((start_z - box.min.z()) / band_height_);
  const int start = std::isnan(band_of_start) ? 0 : static_cast<int>(std::clamp(band_of_start, 0.0, count_ - 1.0));
  for (int k = start; k < count_; ++k) order_.push_back(k);
  for (int k = start - 1; k >= 0; --k) order_.push_back(k);
}

Band LayerManager::band(int index) const {
  Band b;
  b.index = index;
  b.count = count_;
  b.z_min = box_.min.z() + index * band_height_;
  b.z_max = index + 1 == count_ ? box_.max.z() : box_.min.z() + (index + 1) * band_height_;
  return b;
}

std::size_t LayerManager::countUsable(const std::vector<std::uint32_t>& ids) const {
  return static_cast<std::size_t>(
      std::count_if(ids.begin(), ids.end(), [&](std::uint32_t id) { return !blacklist_.count(id); }));
}

void LayerManager::forgetGoneFrontiers(const std::vector<std::uint32_t>& present) {
  // Ids only grow, and a frontier whose cells change comes back under a new one: an id at or below the
  // highest yet seen that is not in the list now is gone for good, and so are its records. A higher one
  // (a failure reported against frontiers newer than the list here) is kept until a list shows it.
  for (std::uint32_t id : present) highest_seen_ = std::max(highest_seen_, id);
  if (failures_.empty()) return;
  std::vector<std::uint32_t> sorted(present);
  std::sort(sorted.begin(), sorted.end());
  auto gone = [&](std::uint32_t id) { return id <= highest_seen_ && !std::binary_search(sorted.begin(), sorted.end(), id); };
  for (auto it = failures_.begin(); it != failures_.end();) it = gone(it->first) ? failures_.erase(it) : std::next(it);
  for (auto it = blacklist_.begin(); it != blacklist_.end();) it = gone(*it) ? blacklist_.erase(it) : std::next(it);
}

LayerOutputs LayerManager::output() const {
  LayerOutputs out;
  out.state = state_;
  out.reason = reason_;
  if (state_ == ExplorationState::kFinalPass || state_ == ExplorationState::kFinished) {
    out.band.index = 0;
    out.band.count = count_;
    out.band.z_min = box_.min.z();
    out.band.z_max = box_.max.z();
    out.band.final_pass = state_ == ExplorationState::kFinalPass;
  } else {
    out.band = band(order_[position_]);
  }
  return out;
}

LayerOutputs LayerManager::step(const LayerInputs& in, double t) {
  std::vector<Transition> transitions;
  bool ignored = false;
  // `next_position`: the band (index into order_) the state moves to, when it changes.
  auto go = [&](ExplorationState to, const std::string& why, std::optional<std::size_t> next_position = std::nullopt) {
    const int from_band = state_ == ExplorationState::kExplore ? order_[position_] : -1;
    const ExplorationState from = state_;
    state_ = to;
    if (next_position) position_ = *next_position;
    const int to_band = state_ == ExplorationState::kExplore ? order_[position_] : -1;
    transitions.push_back({from, to, from_band, to_band, why});
    empty_since_ = -1.0;
  };
  auto finish = [&](FinishReason r, const std::string& why) {
    reason_ = r;
    go(ExplorationState::kFinished, why);
  };

  // Failed attempts: blacklist after max_retries, so unreachable frontiers cannot hold
  // exploration open forever.
  for (std::uint32_t id : in.failed)
    if (++failures_[id] >= config_.max_retries) blacklist_.insert(id);
  forgetGoneFrontiers(in.all_frontiers);

  // A stop request ends the exploration at once, from any state but FINISHED (a trigger with it is void).
  if (in.abort && state_ != ExplorationState::kFinished) finish(FinishReason::kAborted, "stopped on request");
  if (state_ == ExplorationState::kWaitTrigger) {
    if (in.trigger) {
      t_trigger_ = t;
      progress_time_ = t;
      last_progress_ = in.map_progress;
      progress_position_ = in.position;
      position_ = 0;
      go(ExplorationState::kExplore, "triggered");
    }
  } else if (in.trigger) {
    ignored = true;
  }

  if (in.yaw && std::isfinite(*in.yaw) && state_ != ExplorationState::kWaitTrigger) {
    const double turns = *in.yaw / (2.0 * M_PI);
    const int octant = static_cast<int>(std::floor(8.0 * (turns - std::floor(turns)))) & 7;
    headings_seen_ |= 1u << octant;
  }
  if (state_ == ExplorationState::kExplore || state_ == ExplorationState::kFinalPass) {
    // Progress: the map changed, or the vehicle got progress_travel from where it was at the last
    // progress (a long transit through mapped space changes no voxel; jitter in place does not count).
    if (in.relocalised && in.position) progress_position_ = in.position;
    const bool flown = in.position && progress_position_ && config_.progress_travel > 0.0 &&
                       (*in.position - *progress_position_).norm() >= config_.progress_travel;
    const bool progress = in.map_progress != last_progress_ || flown;
    if (progress) progress_time_ = t;
    if (progress || !progress_position_) {  // the position too once it is first known
      last_progress_ = in.map_progress;
      progress_position_ = in.position;
    }
    if (t - t_trigger_ >= config_.time_limit) {
      finish(FinishReason::kTimeLimit, "time limit reached");
    } else if (t - progress_time_ >= config_.stuck_timeout) {
      finish(FinishReason::kStuck, "no map progress nor " + std::to_string(config_.progress_travel) + " m flown for " +
                                       std::to_string(config_.stuck_timeout) + " s");
    }
  }
  // A band (or, in the final pass, the box) without usable frontiers for settle_time is
  // done, once the camera has looked round (else the chain is asked to turn in place: a start facing a
  // wall sees too little for a frontier and would end the run "complete" at once). The next band's
  // frontiers arrive with the next inputs.
  bool look_around = false;
  const std::size_t usable_in_box = countUsable(in.all_frontiers);
  const std::size_t blacklisted_left = in.all_frontiers.size() - usable_in_box;
  if (state_ == ExplorationState::kExplore || state_ == ExplorationState::kFinalPass) {
    const bool final_pass = state_ == ExplorationState::kFinalPass;
    if (!in.frontiers_known || countUsable(in.band_frontiers) > 0) {
      empty_since_ = -1.0;
    } else if (empty_since_ < 0.0) {
      empty_since_ = t;
    }
    if (!in.frontiers_known || usable_in_box > 0) {
      box_empty_since_ = -1.0;
    } else if (box_empty_since_ < 0.0) {
      box_empty_since_ = t;
    }
    // Blacklisted frontiers are left unexplored: say how many, so a "complete" that is not is visible.
    auto finish_complete = [&] {
      finish(FinishReason::kComplete, blacklisted_left == 0 ? std::string("no frontier left in the box")
                                                            : "no reachable frontier left in the box (" +
                                                                  std::to_string(blacklisted_left) +
                                                                  " blacklisted after failed attempts)");
    };
    auto settled = [&](double empty_since) { return empty_since >= 0.0 && t - empty_since >= config_.settle_time; };
    // The final pass's wait counts from when the box became empty, which may be before the pass began.
    if (settled(final_pass ? box_empty_since_ : empty_since_)) {
      if (!lookedAround()) {
        look_around = true;
      } else if (final_pass) {
        finish_complete();
      } else if (position_ + 1 < order_.size()) {
        go(ExplorationState::kExplore, "band explored", position_ + 1);
      } else {
        go(ExplorationState::kFinalPass, "every band explored");
        // The whole box has already been without usable frontiers for settle_time (with one band
        // covering the box, always): the final pass has nothing to find, and waiting out its own
        // settle_time would only add that much to every run.
        if (settled(box_empty_since_)) finish_complete();
      }
    }
  }

  LayerOutputs out = output();
  out.blacklisted_left = blacklisted_left;
  out.transitions = std::move(transitions);
  out.trigger_ignored = ignored;
  out.look_around = look_around;
  return out;
}

}  // namespace go_feap::planning
