#include "nestlight/gi/environment_source.h"

namespace nestlight::gi {

EnvironmentSource::EnvironmentSource(const std::optional<SceneEnvironment>& e) {
  if (!e) {
    still_ = std::make_shared<EnvironmentMap>();
    return;
  }
  present_ = true;
  if (e->constant) {
    // A constant's `scale` multiplies it as it does a map.
    still_ = std::make_shared<EnvironmentMap>(EnvironmentMap::constant(*e->constant * e->scale));
  } else if (!e->sequence.empty()) {
    sequence_ = std::make_unique<EnvironmentSequence>(sequenceSpec(*e));
  } else {
    still_ = std::make_shared<EnvironmentMap>(
        EnvironmentMap::load(e->path.string(), e->rotationDegrees, e->scale));
  }
}

size_t EnvironmentSource::frameAt(double seconds) const {
  return sequence_ ? sequence_->frameAt(seconds) : 0;
}

size_t EnvironmentSource::frames() const {
  return sequence_ ? sequence_->frames() : 1;
}

std::shared_ptr<const EnvironmentMap> EnvironmentSource::at(double seconds) {
  if (!sequence_) return still_;
  return sequence_->frame(sequence_->frameAt(seconds));
}

}  // namespace nestlight::gi
