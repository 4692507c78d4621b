#pragma once

#include "rastercheck/collision/CollisionRequest.h"

namespace rastercheck
{
/** \brief What a CollisionMode allows each test to decide, written once for every backend: the CPU
    backend's pair decision (CpuBackend) and the batched stages' settings (stageSettings) read the
    same rules, so the modes cannot drift apart between them. */
struct ModeRules
{
    /** \brief The hull proofs may settle a pair as overlapping. Such a proof names no triangle, so
        only when no contact is asked; never in raster mode, whose verdicts (misses included) must
        not depend on whether contacts are asked. */
    bool proveOverlaps;
    /** \brief A non-convex mesh obstacle (a scene object with patches) goes straight to the exact
        phase, its trees culling as well as the proofs would: every mode but raster, whose
        verdicts are the raster's. */
    bool meshObstaclesExact;
    /** \brief A pair that no proof settles collides (conservative mode: its verdicts are the
        proofs' outcome, with no exact phase). */
    bool unprovenCollides;
    /** \brief The proofs may start from the direction that last proved a pair apart in the same
        workspace. Not in conservative mode, whose verdicts are the proofs' outcome and must not
        depend on what the workspace decided before. */
    bool warmStart;
    /** \brief Conservative mode's proofs walk one solid's patches against the other's (near-exact
        among non-convex meshes with no exact phase behind them); where the exact phase follows on
        the same core the walk costs more than it saves (device::relateSolids). */
    bool patchAgainstPatch;
    /** \brief The joint-space clearance tables may prove a self pair apart: safe and exact mode,
        whose verdicts are the meshes' own (the others' are their tests' outcomes). */
    bool clearanceTables;
    /** \brief The raster decides the pairs the proofs leave, on the CPU backend: raster mode only
        (elsewhere the exact phase on the same core is faster than rasterizing). */
    bool rasterOnHost;
    /** \brief The batched stages rasterize the pairs the proofs leave: raster mode, and safe mode
        without contacts, where a raster hit is proof enough (a contact asked takes the exact phase
        on every pair, to report the CPU's first contact). */
    bool rasterInStages;
    /** \brief A raster miss goes on to the exact phase (safe mode); elsewhere it stands, but padding
        is always honoured exactly, as the raster sees overlaps, not distances. */
    bool confirmRasterMisses;
};

/** \brief The rules of \a mode, for a call that asks for contacts or not. */
inline ModeRules modeRules(CollisionMode mode, bool contactsAsked)
{
    ModeRules rules{};
    rules.proveOverlaps = !contactsAsked && mode != CollisionMode::Raster;
    rules.meshObstaclesExact = mode != CollisionMode::Raster;
    rules.unprovenCollides = mode == CollisionMode::Conservative;
    rules.warmStart = mode != CollisionMode::Conservative;
    rules.patchAgainstPatch = mode == CollisionMode::Conservative;
    rules.clearanceTables = mode == CollisionMode::Safe || mode == CollisionMode::Exact;
    rules.rasterOnHost = mode == CollisionMode::Raster;
    rules.rasterInStages = mode == CollisionMode::Raster || (mode == CollisionMode::Safe && !contactsAsked);
    rules.confirmRasterMisses = mode == CollisionMode::Safe;
    return rules;
}
}  // namespace rastercheck
