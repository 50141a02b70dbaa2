// How many of a receiver's importance samples each cluster gets (Maletz, Wang and Bowers,
// "Importance-Driven Point Projection for GPU-based Final Gathering", 2011, section 4.1): the
// clusters are visited in order, so no CDF is built or searched. The paper carries each
// cluster's fractional residual into the next with a uniform number per cluster; a negative
// carry (a cluster rounded up) is then clamped at zero where the next expectation is smaller,
// and the debt moves on, so clusters of small pdf behind it get too much (measured: 0.195
// samples on average where N p_k = 0.066) and clusters of zero pdf get samples. Here the carry is
// the running expectation's: cluster k receives floor(F_k + u) - floor(F_(k-1) + u) with
// F_k = N (p_1 + ... + p_k) and one uniform u per receiver (systematic sampling): each count is
// floor or ceil of N p_k, its expectation exactly N p_k, zero where p_k is, and the counts sum to
// N (a float F_K short of N gives what is missing to the last cluster of nonzero pdf). A pdf of
// zeros (no cluster seen) or one whose sum overflows is taken as uniform, and reported (return
// value false).
//
// Defined by the includer before this file: PROJECTION_ALLOCATE_K (clusters), and
//   float allocateWeight(int k)        cluster k's unnormalised probability (>= 0)
//   void allocateStore(int k, int n)   sets cluster k's count
//   int allocateLoad(int k)            reads it back

bool allocateSamples(int total, float u) {
  float sum = 0.0;
  for (int k = 0; k < PROJECTION_ALLOCATE_K; ++k) sum += allocateWeight(k);
  bool weighted = sum > 0.0 && !isinf(sum);
  float scale = weighted ? float(total) / sum : 0.0;
  float even = float(total) / float(PROJECTION_ALLOCATE_K);
  float running = 0.0;
  int before = 0, lastPositive = PROJECTION_ALLOCATE_K - 1;
  for (int k = 0; k < PROJECTION_ALLOCATE_K; ++k) {
    float expected = weighted ? allocateWeight(k) * scale : even;
    running += expected;
    int upTo = min(int(floor(running + u)), total);
    int n = max(upTo - before, 0);
    allocateStore(k, n);
    before += n;
    if (expected > 0.0) lastPositive = k;
  }
  if (before < total) allocateStore(lastPositive, allocateLoad(lastPositive) + total - before);
  return weighted;
}
