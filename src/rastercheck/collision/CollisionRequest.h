#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rastercheck
{
/** \brief How a state is decided. Every mode checks bounds, the environment and (unless disabled)
    self-collision with the allowed-collision matrix, and honours padding exactly. In every mode a
    pair that survives the paper's box culls first gets the convex separation proof
    (device/Separation.h), which settles it as apart only when a plane provably keeps the solids
    more than the padding apart, and, in safe and exact mode when no contact is asked, as colliding
    when a point provably lies inside both; what the modes differ in is the pairs those proofs
    leave. */
enum class CollisionMode
{
    /** \brief Default: never calls a colliding state valid. Every pair the proof leaves is decided
        exactly. The CPU backend decides such pairs with the exact narrow phase directly, because on
        a CPU that is faster than rasterizing them (docs/benchmarks.md); a GPU backend, which
        rasterizes a whole batch in one pass, may settle pairs by the raster first (a parity hit is
        an overlap) and must confirm every other pair exactly. */
    Safe,
    /** \brief The paper's method for the pairs the proof leaves: rays through pixel centres only,
        so overlaps thinner than a pixel or seen edge-on can be missed (measured in
        docs/accuracy.md). Pairs of two open meshes, pairs so far from CollisionModel::origin that
        float rounding exceeds a tenth of a pixel, and padding still go to the exact narrow phase. */
    Raster,
    /** \brief The exact narrow phase (triangle-triangle plus point-in-solid) on every pair the
        proof leaves: exact answers. The tests' oracle (bruteForceCollides) is that narrow phase
        on every pair with no cull at all. */
    Exact,
    /** \brief Every pair the proofs leave counts as colliding: a state is valid only when the culls
        and the separation proof show every pair more than the padding apart. Never calls a
        colliding state valid; calls a free state invalid where two solids' hulls come within the
        padding but their meshes do not (a link reaching into a shelf; measured in
        docs/accuracy.md). The cheapest mode, and the one CertifiedMotionValidator uses for its
        margins, where a false alarm only costs a finer sample. A contact it cannot place names the
        pair, triangle -1, at the centre of the region where their boxes meet. A non-convex mesh
        obstacle (a scene object with patches: a room, a terrain, an OMPL.app environment) is
        decided by the exact phase instead, on both backends: its oriented-box trees make that as
        cheap as the proofs, and the answer exact. */
    Conservative
};

std::string toString(CollisionMode mode);
/** \brief "safe", "raster", "exact" or "conservative"; throws ConfigurationError otherwise. */
CollisionMode parseCollisionMode(const std::string &text);

/** \brief Padding added to CollisionRequest::padding for individual pairs. CertifiedMotionValidator
    gives each pair the distance its two solids can close in over an interval of an edge, so that a
    pair far from the robot's fast-moving links is not held to their margin. */
struct PairPadding
{
    /** \brief Per component (CollisionModel order), for its pairs with every scene object; \a rows
        rows of numComponents() entries. */
    std::vector<double> environment;
    /** \brief Per self pair, in CollisionModel::selfPairs order; \a rows rows of selfPairs.size()
        entries. */
    std::vector<double> self;
    /** \brief 1: one row for every state of a batch. n (the batch's size, Checker::check): row i for
        state i, so that one batch can hold states that need different paddings (the midpoints of
        many edges, each with its own sweeps: CertifiedMotionValidator::checkMotions, which the
        batch planners call). */
    std::size_t rows = 1;
};

/** \brief A state's verdict at two paddings (Checker::checkTwoPaddings): nonzero = valid at the
    request's own paddings. */
enum class PaddedVerdict : std::uint8_t
{
    Collides = 0,  ///< in collision at the request's paddings (or outside the bounds)
    Clear = 1,     ///< clear at the wider paddings too
    Near = 2       ///< clear at the request's paddings, not at the wider ones
};

/** \brief Throws ConfigurationError, naming \a name, unless every entry of \a rows is finite and >= 0. */
void validateEntries(const PairPadding &rows, const std::string &name);

/** \brief What to check and how (Coal/FCL style). */
struct CollisionRequest
{
    CollisionMode mode = CollisionMode::Safe;
    /** \brief Safety margin (metres, or the scene's units): solids closer than this collide. */
    double padding = 0.0;
    /** \brief Raster pixel side (world units); 0 uses CollisionModel::defaultPixelSize. */
    double pixelSize = 0.0;
    /** \brief Largest image side per pair; a larger window gets proportionally larger pixels. */
    int maxImageSide = 64;
    bool checkEnvironment = true;
    bool checkSelfCollision = true;
    /** \brief Optional extra padding per pair (null: none); a pair's solids collide when closer than
        padding + their entry. Each entry finite and >= 0, one per component and per self pair of
        the checker's model in each row, one row or one per state (Checker::check throws
        ConfigurationError otherwise). Every backend takes it, the GPU stages included. */
    std::shared_ptr<const PairPadding> pairPadding;
};

/** \brief Throws ConfigurationError unless padding is finite and >= 0 (a negative margin has no
    meaning for a validity check, and NaN would make every box test false), pixelSize is finite and
    >= 0 (0 = automatic) and maxImageSide is in [1, 4096] (an image is maxImageSide^2 pixels). A
    huge finite padding is allowed: every solid within that reach collides. Checker::check and
    isValid call it on every call (a request is not a state: a bad one is a programming error). */
void validate(const CollisionRequest &request);

/** \brief Why a state is invalid, and where: the first contact found (deterministic: pairs are
    visited in a fixed order). */
struct Contact
{
    enum class Kind : std::uint8_t
    {
        None,          ///< the state is valid
        OutOfBounds,   ///< a coordinate is outside the bounds, not finite, or a quaternion is zero
        Environment,   ///< component vs scene object
        SelfCollision  ///< component vs component
    };
    Kind kind = Kind::None;
    int component = -1;       ///< Party-1 component index
    int object = -1;          ///< scene object index (Environment)
    int otherComponent = -1;  ///< second component (SelfCollision)
    /** \brief Triangle of the object (or other component) at the contact; -1 when the contact was
        found by containment (one solid inside the other, surfaces apart). */
    int triangle = -1;
    /** \brief OutOfBounds: the first coordinate (RobotModel::coordinateNames index) outside its bounds
        or not finite, or a zero quaternion's qx; -1 otherwise. */
    int coordinate = -1;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< world frame
};

/** \brief "none", "out_of_bounds", "environment" or "self": the kind's name in the viewer's JSON API
    and the Python module's contacts. */
std::string toString(Contact::Kind kind);
}  // namespace rastercheck
