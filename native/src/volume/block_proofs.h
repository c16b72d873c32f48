// Internal: proofs that a block of the polygonizer's grid holds no surface, so that it needs
// no samples (the work follows the surface, thesis section 5.1.2).
//
// A block of kSampleBlock^3 nodes is proven
//  - outside when an upper bound of F over its nodes stays below T: the sum over the particles
//    of w g at the particle's nearest point of the block (g falls with distance);
//  - inside when a lower bound stays at or above T at every node. The bound comes from the
//    kernels' convexity in s = |x - p|^2 / R^2 (each of the four is convex on [0, inf) and
//    0 beyond 1): g(s) >= g(s0) + g'(s0) (s - s0) for every s, and since s is quadratic in x,
//
//        F(x) >= F(c) + grad F(c) . (x - c) - K(c) |x - c|^2,   K(c) = sum_i w_i |g'(s_i(c))| / R_i^2,
//
//    for every x. Evaluated at the centre c of each 2 x 2 x 2 group of nodes (64 per block:
//    F, grad F and K summed over the particles, 4 lanes at a time), the bound at the group's
//    nodes (|x - c| = sqrt(3) h / 2) is F(c) - h/2 |grad F(c)|_1 - 3/4 h^2 K(c). Deep inside
//    a fluid (R = 2 spacings, h = R/4) that is about 5.4 against T = 3.3; a bound over a
//    whole block instead (one point, |x - c| = 3.5 sqrt 3 h) falls below zero.
//
// Both bounds are compared with a margin far above the rounding of the float samples they
// stand for, so a proven block's samples would have classified every node the same way: the
// mesh is byte-identical to the one from sampling every block.
//
// The proofs need spherical kernels (one radius, or one per particle) with non-negative
// strengths, and a polynomial kernel for the inside proof; elsewhere every block is sampled.
#pragma once

#include <cstdint>

#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

enum class BlockProof : uint8_t {
  None = 0,     ///< nothing proven: sample the block
  Inside = 1,   ///< every node's sample would be >= T
  Outside = 2,  ///< every node's sample would be < T
};

/// Whether prove_block can prove anything for this field.
bool block_proofs_apply(const ParticleField& field);

/// Try to prove the block whose nodes are first_node + h (i, j, k), 0 <= i, j, k < kSampleBlock.
/// try_inside false: the outside proof only (the inside proof is a pass over the block's
/// particles of about an eighth of its sampling's cost, wasted where it cannot succeed).
BlockProof prove_block(const ParticleField& field, const Vec3& first_node, double h, bool try_inside = true);

}  // namespace particlemesh::detail
