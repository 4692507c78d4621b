#pragma once

#include <string>

#include <Eigen/Core>

#include "rastercheck/collision/CpuBackend.h"

namespace rastercheck::render
{
struct RasterPictureOptions
{
    /** \brief Longest side of the drawn grid (pixels); each image pixel becomes a square cell of a
        whole number of screen pixels, at least one. */
    int gridSide = 768;
    /** \brief First line; empty: "Raster image of the colliding pair". */
    std::string title;
    /** \brief Second line (state, contact); may be empty. */
    std::string subtitle;
    /** \brief Legend names of the pair's two solids (bit 0 and bit 1 of the coverage). */
    std::string componentLabel = "component";
    std::string objectLabel = "object";
};

/** \brief Where a raster picture puts the grid: image pixel (i, j) (column i along u, row j along v,
    as in RasterImage) is the screen square [left + i cell, left + (i + 1) cell) x
    [top + (height - 1 - j) cell, ...): v grows upwards, as world axes do in a plot. */
struct RasterPictureLayout
{
    int width = 0;   ///< PNG pixels
    int height = 0;  ///< PNG pixels
    int left = 0;
    int top = 0;
    int cell = 1;  ///< screen pixels per image pixel
    int gridWidth = 0;
    int gridHeight = 0;

    /** \brief Screen position of the centre of image pixel (i, j). */
    Eigen::Vector2d cellCentre(int i, int j) const;
};

/** \brief The layout writeRasterPicture() uses for \a grid. */
RasterPictureLayout rasterPictureLayout(const device::RasterGrid &grid, const RasterPictureOptions &options = {});

/** \brief The paper's Fig. 6: the image plane of one colliding pair. Cells covered by the component
    only, the other solid only, or both get three colours; cells whose ray finds the solids
    overlapping (RasterImage::hits) are red. The axes carry world coordinates (metres) of the image
    plane's u and v axes, and the caption names the ray axis and the pixel size. Throws
    ConfigurationError when the image's arrays do not match its grid, InputError when the file
    cannot be written. */
RasterPictureLayout writeRasterPicture(const std::string &pngPath, const RasterImage &image,
                                       const RasterPictureOptions &options = {});

/** \brief The same picture as writeRasterPicture(), as the bytes of a PNG file (for a server). */
std::string rasterPicturePng(const RasterImage &image, const RasterPictureOptions &options = {});
}  // namespace rastercheck::render
