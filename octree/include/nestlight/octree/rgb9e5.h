// RGB9E5: three 9-bit mantissas sharing a 5-bit exponent in 32 bits (the layout of GL's
// GL_RGB9_E5 and of EXT_texture_shared_exponent), linear colour from 0 to 65408 with about
// 0.2% relative precision in the largest channel. The GPU point format carries an HDR colour
// layer in it, in the word that otherwise holds the display RGBA8 (shaders/common/colour_word.glsl
// decodes it), and HDR expansion's renderings keep linear colour in it.
#pragma once

#include <cstdint>

namespace nestlight {

// The largest value a channel can hold.
inline constexpr float kRgb9e5Max = 511.0f / 512.0f * 65536.0f;

// Negative and non-finite channels become 0, larger ones clamp to kRgb9e5Max; rounds to nearest.
uint32_t packRgb9e5(float r, float g, float b);
void unpackRgb9e5(uint32_t word, float rgb[3]);

}  // namespace nestlight
