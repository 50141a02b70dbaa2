// A layered sum pyramid in one float buffer: per layer, level 0 (size x size), level 1
// (size/2 x size/2), ... level log2(size) (one value, the layer's total).
int pyramidLevelOffset(int size, int level) {
  int off = 0;
  for (int l = 0; l < level; ++l) off += (size >> l) * (size >> l);
  return off;
}
int pyramidLayerStride(int size) {
  int off = 0;
  for (int s = size; s >= 1; s >>= 1) off += s * s;
  return off;
}
