// Gradient-domain in-fill of HDR colour on a point cloud: Sabbadin, Palma, Banterle, Boubekeur and
// Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.2, eq. 3,
// which carries the idea of Pérez, Gangnet and Blake, "Poisson Image Editing" (2003), from image
// pixels to the k-nearest-neighbour graph of the points. Points whose HDR colour H is unknown (Ω)
// take the values that best match, in the least-squares sense, the gradients of their LDR colour L
// along the graph's edges, with the points of known HDR colour around them (∂Ω) as Dirichlet
// boundary. For p in Ω, with N_p its neighbours:
//   |N_p| H(p) - sum_{q in N_p ∩ Ω} H(q) = sum_{q in N_p ∩ ∂Ω} H(q) + sum_{q in N_p} (L(p) - L(q)).
//
// This is the in-memory core; an out-of-core driver calls it once per chunk, with the chunk's core
// points and a margin of points around it (FixedGuide) whose colour it knows only approximately,
// and keeps the solution of the core's points alone.
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <span>
#include <vector>

namespace nestlight::gi::hdr {

enum class InfillRole : uint8_t {
  Fixed,       // valid HDR colour: part of ∂Ω when a neighbour of a target
  Target,      // in Ω: its HDR colour is solved for
  FixedGuide,  // outside the chunk's core, colour known approximately (an earlier chunk's
               // solution, say): solved exactly as Fixed; a role of its own so a driver's role
               // array can say which points are its margin
};

enum class InfillMode {
  Rgb,        // each channel solved on its own (one matrix, three right-hand sides)
  Luminance,  // solve the luminance of H, then give it L's chromaticity (grey where L is black)
};

enum class InfillPreconditioner {
  IncompleteCholesky,  // fewer iterations on graph Laplacians; the factorisation costs memory
  Diagonal,            // Jacobi: cheapest to build, many more iterations on large regions
};

struct InfillOptions {
  int k = 16;  // neighbours per point, the point itself not counted
  InfillMode mode = InfillMode::Rgb;
  InfillPreconditioner preconditioner = InfillPreconditioner::IncompleteCholesky;
  // Conjugate gradients stop when |b - A x| <= tolerance |b| (Eigen's criterion).
  double tolerance = 1e-6;
  int maxIterations = 2000;
  // What a target gets when it cannot be solved for (an island of targets with no valid
  // neighbour, or a target whose position is not finite): islandScale * L, its LDR colour
  // unexpanded by default.
  float islandScale = 1.0f;
};

struct InfillStats {
  uint64_t targets = 0;           // points given the Target role
  uint64_t solved = 0;            // targets that went into the linear solve
  uint64_t islands = 0;           // connected groups of targets with no valid neighbour
  uint64_t islandPoints = 0;      // the targets in them, given islandScale * L
  uint64_t cgIterations = 0;      // the most over the solves (three in Rgb mode)
  double cgError = 0;             // the largest relative residual |b - A x| / |b| over the solves
  bool converged = true;          // every solve reached the tolerance within maxIterations
  uint64_t clampedNegative = 0;   // solved targets with a negative channel, clamped to 0
  uint64_t nonFiniteResults = 0;  // solved targets whose result was not finite: islandScale * L
  // Points with a non-finite position, LDR colour or (for Fixed roles) HDR colour: they are no
  // one's neighbour. Targets among them are counted in excludedTargets too; they get
  // islandScale * L, or 0 when L is not finite.
  uint64_t nonFiniteInputs = 0;
  uint64_t excludedTargets = 0;
};

// positions: in a local frame (the caller subtracts an origin so that floats keep their
// precision); ldr: linear RGB; hdr: read at Fixed and FixedGuide points, written at Target points
// (and only there). All spans have the same length, below 2^32 - 1.
// Throws std::invalid_argument on mismatched lengths or options out of range.
// What became of each point: an out-of-core driver attributes islands to the points it keeps.
enum class InfillOutcome : uint8_t {
  NotTarget,
  Solved,
  Island,  // given islandScale * L: an island, a non-finite input or a non-finite result
};

// `outcome`, when given, is resized to the point count and filled.
InfillStats poissonInfill(std::span<const glm::vec3> positions, std::span<const glm::vec3> ldr,
                          std::span<glm::vec3> hdr, std::span<const InfillRole> role,
                          const InfillOptions& options = {},
                          std::vector<InfillOutcome>* outcome = nullptr);

// CIE Y of linear (Rec. 709 primaries) RGB, the luminance of Luminance mode.
inline double infillLuminance(const glm::vec3& c) {
  return 0.2126 * double(c.r) + 0.7152 * double(c.g) + 0.0722 * double(c.b);
}

}  // namespace nestlight::gi::hdr
