#pragma once
/// Volume, centre of mass and inertia of the solids hapto's objects are: a box, a sphere, a
/// closed triangle surface, and from them a dynamic object's BodyProperties.

#include "hapto/scenes/ConvexHullOf.h"
#include "hapto/scenes/SceneObject.h"

#include <memory>
#include <optional>
#include <span>

namespace hapto {

/// A uniform solid of density 1 kg/m^3: scale `inertiaPerDensity` by a density to get an
/// inertia tensor.
struct SolidProperties {
    double volumeM3 = 0.0;       ///< Volume (m^3), > 0.
    Vec3 centroid{0.0};          ///< Volume centroid (m, the solid's own frame).
    Mat3 inertiaPerDensity{0.0}; ///< Inertia about the centroid per unit density (m^5: kg m^2
                                 ///< per kg/m^3), own axes, symmetric.
};

/// A box of these half extents (m), centred at the origin: V = 8 hx hy hz, Ixx = V (hy^2 +
/// hz^2) / 3 per unit density. [any thread]
SolidProperties boxSolid(const Vec3& halfExtents);

/// A sphere of this radius (m) about the origin: V = 4/3 pi r^3, I = 2/5 V r^2 per unit
/// density on each axis. [any thread]
SolidProperties sphereSolid(double radius);

/// The solid a closed, consistently oriented triangle surface bounds, by the divergence theorem
/// over its triangles (D. Eberly, "Polyhedral Mass Properties (Revisited)", Geometric Tools,
/// 2002, which follows B. Mirtich, "Fast and Accurate Computation of Polyhedral Mass
/// Properties", J. Graphics Tools 1(2), 1996). Outward (counter-clockwise seen from outside)
/// and inward orientation give the same solid. Returns nothing when the enclosed volume is not
/// positive (a flat or self-cancelling surface). [any thread]
std::optional<SolidProperties> surfaceSolid(std::span<const Vec3> vertices,
                                            std::span<const TriangleIndices> triangles);

/// What a dynamic object's mass fills: a box or a sphere itself; a closed mesh the volume it
/// bounds; an open mesh (or a closed one that bounds no volume) its convex hull. A mesh also
/// gets its convex hull, what it collides as.
struct ObjectSolid {
    SolidProperties solid;                  ///< Unit-density properties (own frame).
    std::shared_ptr<const ConvexHull> hull; ///< A mesh's convex hull; null for a box, sphere.
    bool fromHull = false;                  ///< The solid is the mesh's hull (an open mesh).
};

/// The object's solid (see ObjectSolid). Throws std::invalid_argument when a mesh spans no
/// volume (its vertices lie in one plane). [control]
ObjectSolid solidOf(const SceneObject& object);

/// Fills a dynamic object's mass, centre of mass and inertia (when `inertia` is not given) from
/// its solid and either its mass (kg) or its density (kg/m^3), exactly one of which is given,
/// and a mesh's hull. Throws std::invalid_argument as solidOf does, or when the mass computed
/// from the density is not a finite number > 0. [control]
void fillMassProperties(SceneObject& object, std::optional<double> massKg,
                        std::optional<double> densityKgPerM3, std::optional<Mat3> inertia);

} // namespace hapto
