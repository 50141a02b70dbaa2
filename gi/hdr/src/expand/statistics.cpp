// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1: pass A over
// the scan, its luminance histogram (eq. 1) for the exposure search and a sample of its
// over-exposed points for the automatic views.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <mutex>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

uint64_t Sample::hashOf(uint64_t index) {  // splitmix64's finaliser
  uint64_t x = index + 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

void Sample::offer(const Entry& e, size_t capacity) {
  if (heap.size() < capacity) {
    heap.push_back(e);
    std::push_heap(heap.begin(), heap.end());
  } else if (e.hash < heap.front().hash) {
    std::pop_heap(heap.begin(), heap.end());
    heap.back() = e;
    std::push_heap(heap.begin(), heap.end());
  }
}

void Sample::finish() {
  std::sort(heap.begin(), heap.end());
  for (const Entry& e : heap) positions.push_back(e.position), normals.push_back(e.normal);
}

void Expansion::statistics() {
  const auto t = Clock::now();
  std::vector<double> counts(kHistogramBins, 0.0);
  std::atomic<uint64_t> overexposed{0};
  std::mutex mutex;
  const size_t kSampleMax = 20000;
  std::atomic<uint64_t> nodesDone{0};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints == 0) return;
    const ScanNode n = scan.read(key, entry);
    std::vector<double> local(kHistogramBins, 0.0);
    std::vector<size_t> over;
    for (size_t i = 0; i < n.ldr.size(); ++i) {
      const double y = luminance(n.ldr[i]);
      local[size_t(std::clamp(int(y * kHistogramBins), 0, kHistogramBins - 1))] += 1;
      if (y > o.overexposed) over.push_back(i);
    }
    overexposed += over.size();
    std::lock_guard<std::mutex> lock(mutex);
    for (int b = 0; b < kHistogramBins; ++b) counts[size_t(b)] += local[size_t(b)];
    for (size_t i : over)
      sample.offer(
          {Sample::hashOf(base[ni] + i), n.world[i], n.normal.empty() ? glm::vec3(0) : n.normal[i]},
          kSampleMax);
    progress("statistics", double(++nodesDone) / double(nodes.size()));
  });
  rep.overexposed = overexposed;
  sample.finish();
  scanHistogram.counted = rep.points;
  for (int b = 0; b < kHistogramBins; ++b)
    scanHistogram.mass[size_t(b)] = counts[size_t(b)] / double(rep.points);
  rep.seconds["statistics"] = seconds(t);
}

}  // namespace nestlight::gi::hdr::expand
