// The adaptive sampling's cells (Maletz, Wang and Bowers 2011, section 3.3): a pixel on a
// level's grid and the corners of its cell on the coarser grid, with their joint bilateral
// weights (Kopf, Cohen, Lischinski and Uyttendaele, "Joint Bilateral Upsampling", 2007: the
// bilinear weight times the guide's similarity: normals, and the corner's distance from the
// pixel's tangent plane, which is 0 across a tilted plane and large across a depth edge) and
// tone-mapped outgoing radiance. Include after projection_common.glsl.
layout(std430, binding = PROJECTION_SSBO_PIXELS) buffer Pixels { vec4 pixels[]; };
uniform bool uGathers;

// The grids are the full image's (a tile at x0, y0 takes the same pixels as an untiled frame,
// its margin holding the parents its edge pixels need); the image's last row and column are on
// every grid, so that every pixel has corners on both sides.
bool onGrid(ivec2 px, int step, ivec2 size) {
  ivec2 g = px + ivec2(frame.tile.xy), last = ivec2(frame.image.xy) - 1;
  return (g.x % step == 0 || g.x == last.x) && (g.y % step == 0 || g.y == last.y);
}

// A pixel's outgoing radiance from its gathered (or interpolated) light: direct light plus its
// diffuse albedo times the irradiance over pi plus the glossy rest.
vec3 outgoingAt(ivec2 px, ivec2 size) {
  uint i = uint(px.y * size.x + px.x);
  vec3 emission;
  MaterialParams m = gbufferMaterial(texelFetch(uBaseColour, px, 0).rgb, texelFetch(uMaterial, px, 0), emission);
  return texelFetch(uDirect, px, 0).rgb + diffuseAlbedo(m) * kInvPi * pixels[2u * i].rgb + pixels[2u * i + 1u].rgb;
}

struct Corners {
  ivec2 at[4];
  float weight[4];      // joint bilateral weights, normalised (all 0: no corner is like the pixel)
  float weightSum;      // before normalising
  float toneMapped[4];  // L_o's luminance, l / (1 + l)
};

// The coarser grid's cell around px (step 2 x `step`): its corners, clamped to the tile.
Corners cornersOf(ivec2 px, int step, ivec2 size) {
  int s2 = 2 * step;
  ivec2 origin = ivec2(frame.tile.xy), g = px + origin;
  ivec2 lo = (g / s2) * s2;
  ivec2 hi = min(lo + s2, ivec2(frame.image.xy) - 1);
  if (g.x % s2 == 0 || hi.x == g.x) hi.x = lo.x;
  if (g.y % s2 == 0 || hi.y == g.y) hi.y = lo.y;
  vec2 t = vec2(hi.x > lo.x ? float(g.x - lo.x) / float(hi.x - lo.x) : 0.0,
                hi.y > lo.y ? float(g.y - lo.y) / float(hi.y - lo.y) : 0.0);
  // In the tile's pixels; corners beyond the tile (only for its margin's pixels, which the
  // frame discards) are clamped to it.
  lo = clamp(lo - origin, ivec2(0), size - 1);
  hi = clamp(hi - origin, ivec2(0), size - 1);
  Corners c;
  c.at[0] = lo, c.at[1] = ivec2(hi.x, lo.y), c.at[2] = ivec2(lo.x, hi.y), c.at[3] = hi;
  float bilinear[4] = float[4]((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
  vec3 pc = positionAt(px), nc = normalAt(px);
  float footprint = 0.02 * max(length(pc - frame.eye.xyz), 1e-6);
  c.weightSum = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 q = c.at[k];
    uint i = uint(q.y * size.x + q.x);
    float w = 0.0;
    c.toneMapped[k] = 0.0;
    if (pixels[2u * i].w != PROJECTION_UNSET && texelFetch(uDepth, q, 0).r < 1.0) {
      vec3 nq = normalAt(q);
      float plane = abs(dot(positionAt(q) - pc, nc));
      w = bilinear[k] * pow(max(dot(nq, nc), 0.0), 8.0) * max(1.0 - plane / footprint, 0.0);
      float l = luminance(outgoingAt(q, size));
      c.toneMapped[k] = l / (1.0 + l);
    }
    // A corner at the pixel's own bilinear weight 0 still speaks for it when it is the only one.
    c.weight[k] = w;
    c.weightSum += w;
  }
  // Corners the bilinear weights leave out (the pixel on the cell's edge) but that are alike
  // count through the others; a pixel on a corner's row takes only that row's corners.
  if (c.weightSum > 0.0)
    for (int k = 0; k < 4; ++k) c.weight[k] /= c.weightSum;
  return c;
}
