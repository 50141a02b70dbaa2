// The builder's planning: the octree's attribute layout and quantisation grid, from the sources'
// headers (or one measuring pass where they declare no bounds).
#include "builder_passes.h"

namespace nestlight::build_passes {

// Planning visits sources sorted by path, so that the layout and the grid's offset do not
// depend on the order the inputs were given in.
std::vector<SourceState*> Builder::planningOrder() {
  std::vector<SourceState*> order;
  for (auto& s : sources_) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(), [](const SourceState* a, const SourceState* b) {
    return a->reader->header().path < b->reader->header().path;
  });
  return order;
}

void Builder::planLayout() {
  int rgbBits = 0;
  bool rgb16 = false;
  for (SourceState* sp : planningOrder()) {
    SourceState& s = *sp;
    const SourceHeader& h = s.reader->header();
    for (const Attribute& a : h.layout.attributes()) {
      int i = layout_.find(a.name);
      if (i < 0) {
        layout_.add(a);
      } else if (!(layout_[i] == a)) {
        if (layout_[i].components != a.components)
          throw Error(h.path, "",
                      "attribute '" + a.name + "' has " + std::to_string(a.components) +
                          " components here but " + std::to_string(layout_[i].components) +
                          " in another input");
        // Mixed types: widen to double, which holds every integer type up to 32 bits exactly.
        widened_.insert(a.name);
      }
    }
    if (h.layout.has(attr::kRgb)) {
      rgbBits = 8;
      rgb16 = rgb16 || h.rgbBits != 8;
    }
  }
  if (!widened_.empty()) {
    PointLayout l;
    for (Attribute a : layout_.attributes()) {
      if (widened_.count(a.name)) a.type = ScalarType::F64;
      l.add(a);
    }
    layout_ = l;
  }
  meta_.rgbSourceBits = rgbBits ? (rgb16 ? 16 : 8) : 0;
  if (opt_.estimateNormals) {
    bool allHave = !sources_.empty();
    for (auto& s : sources_) allHave = allHave && s.reader->header().layout.has(attr::kNormal);
    if (allHave) {
      progress_.message("every input has normals; --estimate-normals keeps them");
    } else {
      if (!layout_.has(attr::kNormal))
        layout_.add({std::string(attr::kNormal), ScalarType::F32, 3, "estimated"});
      estimate_ = true;
    }
  }
  stride_ = layout_.stride();
  normalIndex_ = layout_.find(attr::kNormal);
  for (auto& s : sources_) {
    const PointLayout& sl = s.reader->header().layout;
    for (size_t i = 0; i < layout_.size(); ++i) {
      AttributeMap::Entry e;
      e.src = sl.find(layout_[i].name);
      e.copy = e.src >= 0 && sl[e.src] == layout_[i];
      s.map.entries.push_back(e);
    }
    s.identity = sl == layout_ && !estimate_;
  }
}

void Builder::planQuantisation(BuildReport& report) {
  // Precision per axis: the inputs' own scales (the finest of each axis where they differ),
  // so that LAS integer coordinates come back out exactly; one --precision for all axes when
  // given.
  Vec3d scales{opt_.precision, opt_.precision, opt_.precision};
  std::optional<Vec3d> base;
  std::set<std::array<double, 3>> seen;
  for (SourceState* sp : planningOrder()) {
    const SourceHeader& h = sp->reader->header();
    if (h.offset && !base) base = h.offset;
    if (opt_.precision <= 0 && h.scale) {
      seen.insert({h.scale->x, h.scale->y, h.scale->z});
      for (int a = 0; a < 3; ++a)
        if ((*h.scale)[a] > 0)
          scales[a] = scales[a] > 0 ? std::min(scales[a], (*h.scale)[a]) : (*h.scale)[a];
    }
  }
  // Axes no input scales: the finest scale any axis has, else a millimetre.
  double finest = 0;
  for (int a = 0; a < 3; ++a)
    if (scales[a] > 0) finest = finest > 0 ? std::min(finest, scales[a]) : scales[a];
  for (int a = 0; a < 3; ++a)
    if (!(scales[a] > 0)) scales[a] = finest > 0 ? finest : 0.001;
  if (seen.size() > 1)
    buildNotes_.push_back(
        "the inputs have " + std::to_string(seen.size()) +
        " different scales; the octree keeps the finest of each axis (" + shortNumber(scales.x) +
        ", " + shortNumber(scales.y) + ", " + shortNumber(scales.z) +
        "): coordinates of the other inputs that are not on that grid are rounded to it");
  report.warnings.insert(report.warnings.end(), buildNotes_.begin(), buildNotes_.end());
  meta_.scale = scales;
  meta_.sourceOffset = base;
  for (int a = 0; a < 3; ++a) invScale_[a] = 1.0 / scales[a];
  const double scale = meta_.maxScale();

  // Bounds: declared ones where a header gives valid bounds, a reading pass for the rest.
  Box3d bounds;
  std::vector<size_t> scan;
  for (size_t i = 0; i < sources_.size(); ++i) {
    auto& s = sources_[i];
    const SourceHeader& h = s.reader->header();
    if (h.declaredBounds && validBox(*h.declaredBounds)) {
      s.declared = *h.declaredBounds;
      double ss = h.scale ? std::max({h.scale->x, h.scale->y, h.scale->z}) : scale;
      s.tolerance = 0.5 * ss;
    }
    // Header bounds are advisory: they spare a reading pass. The grid's first step lies at or
    // below their minimum and the cube holds a step beyond their maximum, so points rounded
    // half a step past them (bounds computed before quantisation) still fit; a point beyond
    // the cube restarts the conversion with the bounds measured (OutsideCube).
    if (s.declared && !measureBounds_) {
      bounds.extend(*s.declared);
    } else if (s.owned) {
      scan.push_back(i);  // another rank measures the inputs it reads
    }
  }
  if (!scan.empty()) {
    auto t = Clock::now();
    uint64_t total = 0;
    for (size_t i : scan) total += sources_[i].reader->bytesTotal();
    progress_.begin("bounds", total, "bytes");
    PointBatch batch;
    for (size_t i : scan) {
      auto& r = *sources_[i].reader;
      r.rewind();
      uint64_t before = 0;
      while (r.read(batch, kBatchPoints)) {
        const double* p = batch.xyz.data();
        for (size_t k = 0, n = batch.size(); k < n; ++k, p += 3)
          if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
            bounds.extend(p[0], p[1], p[2]);
        progress_.advance(r.bytesConsumed() - before, batch.size());
        before = r.bytesConsumed();
      }
    }
    progress_.end();
    report.phases["bounds"] = seconds(t);
  }
  if (distributed()) {
    std::vector<double> b{-bounds.min.x, -bounds.min.y, -bounds.min.z,
                          bounds.max.x,  bounds.max.y,  bounds.max.z};
    comm_->allreduceMax(b);
    bounds.min = {-b[0], -b[1], -b[2]};
    bounds.max = {b[3], b[4], b[5]};
  }
  if (bounds.empty()) {
    meta_.offset = {0, 0, 0};
    meta_.cubeSize = 1;
    meta_.spacing = meta_.cubeWorldSize() / 128.0;
    return;
  }
  // The integer grid keeps the input's: offsets step from the first LAS offset in whole scales,
  // so that LAS integer coordinates map to ours without rounding.
  Vec3d b = base.value_or(Vec3d{0, 0, 0});
  double extent = 0;
  for (int a = 0; a < 3; ++a) {
    const double sa = scales[a];
    meta_.offset[a] = b[a] + std::floor((bounds.min[a] - b[a]) / sa) * sa;
    const double steps = std::ceil((bounds.max[a] - meta_.offset[a]) / sa) + 1;
    if (!(steps < double(uint64_t(1) << 31)))
      throw Error("", "",
                  "the scan spans " + std::to_string(steps * sa) + " units along " +
                      std::string(1, "xyz"[a]) + ", more than 2^31 steps of " + std::to_string(sa) +
                      "; use a coarser --precision");
    extent = std::max(extent, steps);
  }
  uint64_t cube = 1;
  while (cube < extent) cube <<= 1;
  meta_.cubeSize = static_cast<uint32_t>(cube);
  meta_.spacing = meta_.cubeWorldSize() / 128.0;  // the root's; nodes measure theirs against it
}

}  // namespace nestlight::build_passes
