// The sRGB transfer function (IEC 61966-2-1:1999): how 8- and 16-bit scan and mesh colours are
// decoded to linear values, and how the tone map encodes them back. One definition for gi.
#pragma once

namespace nestlight::gi {

// Linear [0, 1] (clamped) to the encoded value; 1 stays exactly 1.
float srgbEncode(float linear);
// Encoded [0, 1] (clamped) to linear.
float srgbDecode(float encoded);

}  // namespace nestlight::gi
