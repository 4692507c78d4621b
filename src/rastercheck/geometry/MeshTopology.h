#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rastercheck/geometry/Mesh.h"

namespace rastercheck
{
/** \brief What the load-time mesh check found. The parity test of the raster pipeline needs a
    closed, consistently oriented surface; an open mesh is checked by the exact narrow phase. */
struct MeshTopology
{
    bool closed = false;                  ///< every edge shared by exactly two triangles, consistently oriented
    std::size_t boundaryEdges = 0;        ///< edges used by one triangle (holes)
    std::size_t nonManifoldEdges = 0;     ///< edges used by more than two triangles
    std::size_t misorientedEdges = 0;     ///< edges whose two triangles traverse it in the same direction
    std::size_t degenerateTriangles = 0;  ///< removed: zero area or repeated vertex
    std::size_t mergedVertices = 0;       ///< coincident vertices welded
    std::size_t removedDuplicateFaces = 0;  ///< double-sided copies (front and back) removed
    std::size_t shells = 0;  ///< connected pieces (triangles linked through shared vertices)

    /** \brief One line for `rastercheck info` and warnings, e.g. "closed" or
        "open (12 boundary edges, 2 non-manifold)". */
    std::string summary() const;
};

/** \brief Cleans \a mesh in place and reports its topology: welds vertices closer than
    \a weldTolerance (metres), drops degenerate triangles, removes duplicate faces (the same three
    vertices, either orientation: SketchUp COLLADA stores every face front and back, which would
    toggle parity twice), then checks closedness and orientation. Each closed shell oriented inward
    (negative signed volume) is flipped so normals point out. */
MeshTopology cleanMesh(Mesh &mesh, double weldTolerance = 1e-9);

/** \brief Cleans each part on its own, then concatenates them into \a merged. No welding across
    parts: two collision elements of a link that touch or overlap stay two closed shells (welding
    would make their shared edges non-manifold). The result is closed when every part is. */
MeshTopology cleanAndMerge(std::vector<Mesh> parts, Mesh &merged, double weldTolerance = 1e-9);

/** \brief The connected shell of every triangle (triangles linked through shared vertices),
    numbered 0..shells-1 in order of first appearance. */
std::vector<std::uint32_t> triangleShells(const Mesh &mesh, std::size_t &shells);

/** \brief Signed volume (positive for outward-oriented closed meshes). */
double signedVolume(const Mesh &mesh);
}  // namespace rastercheck
