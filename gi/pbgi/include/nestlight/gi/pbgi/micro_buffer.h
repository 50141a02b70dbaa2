// Micro-buffers of point-based GI (Ritschel et al. 2009, "Micro-Rendering for Scalable, Parallel
// Final Gathering"; Sabbadin et al., "High Dynamic Range Point Clouds for Real-Time Relighting",
// 2019, sections 5.2 and 5.3): a receiver's hemisphere of incoming radiance as an M x M
// paraboloid map (Heidrich and Seidel 1998) about its normal.
//
// The paraboloid maps a direction w (z along the normal) to (x, y) / (1 + z) in the unit disc.
// Its m-pixels are not equal in solid angle (4 / (1 + s^2 + t^2)^2 per unit map area: 4x more at
// the pole than at the horizon), so eq. 7's quadrature takes each m-pixel's own solid angle
// Omega_ij. This table integrates them over each m-pixel's square clipped to the disc (16 x 16
// sub-samples): the solid angles sum to 2 pi and their cosine-weighted sum to pi, to the
// sub-sampling's accuracy, so a uniform hemisphere of radiance L reflects exactly rho L from a
// Lambert receiver. The cut test (eq. 4) compares a node's solid angle with the paper's constant
// m-pixel solid angle: the hemisphere's 2 pi over the M^2 m-pixels.
#pragma once

#include <glm/glm.hpp>
#include <vector>

namespace nestlight::gi::pbgi {

// Map coordinates in [-1, 1]^2 of a direction with z >= 0 (z: the receiver's normal).
glm::vec2 paraboloidFromDirection(const glm::vec3& w);
// Its inverse on the unit disc (a unit vector with z >= 0).
glm::vec3 directionFromParaboloid(const glm::vec2& st);

struct MicroBufferTable {
  int size = 0;  // M
  // Per m-pixel, row-major from (s, t) = (-1, -1): xyz the mean of its directions over its
  // solid angle (not normalised: its z is then exactly the m-pixel's mean cosine; normalise it
  // for the BRDF's direction), w its solid angle Omega_ij. Both 0 outside the disc.
  std::vector<glm::vec4> texels;
  float solidAngleSum() const;
  float cosineWeightedSum() const;  // sum of Omega_ij cos(theta_ij)
};

MicroBufferTable microBufferTable(int size);

// The paper's constant m-pixel solid angle for the cut test: 2 pi / M^2.
float mPixelSolidAngle(int size);

}  // namespace nestlight::gi::pbgi
