#include "render/RasterPicture.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rastercheck/core/Error.h"
#include "render/Canvas.h"

namespace rastercheck::render
{
using detail::Anchor;
using detail::Colour;
using detail::kInk;

namespace
{
constexpr int kRasterLeftMargin = 80, kRasterRightMargin = 40, kRasterTopMargin = 74, kRasterBottomMargin = 110;
constexpr int kRasterMinimumWidth = 720;

const Colour kEmpty{0.97, 0.97, 0.96};
const Colour kComponentOnly{0.45, 0.64, 0.87};
const Colour kObjectOnly{0.82, 0.76, 0.62};
const Colour kBoth{0.56, 0.47, 0.70};
const Colour kHit{0.9, 0.05, 0.05};

const char *axisName(int axis)
{
    return axis == 0 ? "x" : (axis == 1 ? "y" : "z");
}
}  // namespace

Eigen::Vector2d RasterPictureLayout::cellCentre(int i, int j) const
{
    return {left + (i + 0.5) * cell, top + (gridHeight - 1 - j + 0.5) * cell};
}

RasterPictureLayout rasterPictureLayout(const device::RasterGrid &grid, const RasterPictureOptions &options)
{
    RasterPictureLayout layout;
    layout.gridWidth = std::max(1, grid.width);
    layout.gridHeight = std::max(1, grid.height);
    layout.cell = std::max(1, options.gridSide / std::max(layout.gridWidth, layout.gridHeight));
    layout.left = kRasterLeftMargin;
    layout.top = kRasterTopMargin;
    layout.width =
        std::max(kRasterMinimumWidth, kRasterLeftMargin + layout.gridWidth * layout.cell + kRasterRightMargin);
    layout.height = kRasterTopMargin + layout.gridHeight * layout.cell + kRasterBottomMargin;
    return layout;
}

namespace
{
/** \brief The layout of \a image's picture; throws ConfigurationError when its arrays do not match
    its grid. */
RasterPictureLayout checkedLayout(const RasterImage &image, const RasterPictureOptions &options)
{
    const device::RasterGrid &grid = image.grid;
    const std::size_t pixels = static_cast<std::size_t>(std::max(0, grid.width)) * std::max(0, grid.height);
    if (pixels == 0 || image.coverage.size() != pixels || image.hits.size() != pixels || !(grid.pixel > 0))
        throw ConfigurationError("raster picture: the image's coverage and hits do not match its " +
                                 std::to_string(grid.width) + " x " + std::to_string(grid.height) + " grid");
    return rasterPictureLayout(grid, options);
}

/** \brief Paints the picture of \a image onto \a canvas, made layout.width x layout.height. */
void paintRasterPicture(detail::Canvas &canvas, const RasterImage &image, const RasterPictureLayout &layout,
                        const RasterPictureOptions &options)
{
    const device::RasterGrid &grid = image.grid;
    cairo_t *cr = canvas.context();
    const int cell = layout.cell;
    const double gridW = grid.width * cell, gridH = grid.height * cell;

    std::size_t hits = 0;
    for (int j = 0; j < grid.height; ++j)
        for (int i = 0; i < grid.width; ++i)
        {
            const std::size_t p = static_cast<std::size_t>(j) * grid.width + i;
            const int coverage = image.coverage[p] & 3;
            const Colour &colour =
                image.hits[p]
                    ? kHit
                    : (coverage == 3 ? kBoth
                                     : (coverage == 1 ? kComponentOnly : (coverage == 2 ? kObjectOnly : kEmpty)));
            hits += image.hits[p] ? 1 : 0;
            cairo_rectangle(cr, layout.left + i * cell, layout.top + (grid.height - 1 - j) * cell, cell, cell);
            detail::setColour(cr, colour);
            cairo_fill(cr);
        }
    // Cell borders only where cells are large enough for them to help rather than grey the image.
    if (cell >= 6)
    {
        cairo_set_source_rgba(cr, 1, 1, 1, 0.6);
        cairo_set_line_width(cr, 1.0);
        for (int i = 1; i < grid.width; ++i)
        {
            cairo_move_to(cr, layout.left + i * cell + 0.5, layout.top);
            cairo_line_to(cr, layout.left + i * cell + 0.5, layout.top + gridH);
        }
        for (int j = 1; j < grid.height; ++j)
        {
            cairo_move_to(cr, layout.left, layout.top + j * cell + 0.5);
            cairo_line_to(cr, layout.left + gridW, layout.top + j * cell + 0.5);
        }
        cairo_stroke(cr);
    }
    cairo_rectangle(cr, layout.left - 0.5, layout.top - 0.5, gridW + 1, gridH + 1);
    detail::setColour(cr, kInk);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);

    // Ticks in world coordinates of the image plane.
    const int u = (grid.axis + 1) % 3, v = (grid.axis + 2) % 3;
    const double uSpan = grid.width * grid.pixel, vSpan = grid.height * grid.pixel;
    const double step = detail::niceStep(std::max(uSpan, vSpan), 6);
    const double scale = cell / static_cast<double>(grid.pixel);
    cairo_set_line_width(cr, 1.0);
    for (double w = std::ceil(grid.origin[0] / step) * step; w <= grid.origin[0] + uSpan + 1e-9; w += step)
    {
        const double x = layout.left + (w - grid.origin[0]) * scale;
        cairo_move_to(cr, x, layout.top + gridH);
        cairo_line_to(cr, x, layout.top + gridH + 5);
        cairo_stroke(cr);
        detail::drawText(cr, detail::formatTick(w, step), x, layout.top + gridH + 18, 11, Anchor::Centre);
    }
    for (double w = std::ceil(grid.origin[1] / step) * step; w <= grid.origin[1] + vSpan + 1e-9; w += step)
    {
        const double y = layout.top + gridH - (w - grid.origin[1]) * scale;
        cairo_move_to(cr, layout.left - 5, y);
        cairo_line_to(cr, layout.left, y);
        cairo_stroke(cr);
        detail::drawText(cr, detail::formatTick(w, step), layout.left - 8, y + 4, 11, Anchor::Right);
    }
    detail::drawText(cr, std::string(axisName(u)) + " (m)", layout.left + gridW / 2, layout.top + gridH + 36, 12,
                     Anchor::Centre);
    cairo_save(cr);
    cairo_translate(cr, 20, layout.top + gridH / 2);
    cairo_rotate(cr, -M_PI / 2);
    detail::drawText(cr, std::string(axisName(v)) + " (m)", 0, 0, 12, Anchor::Centre);
    cairo_restore(cr);

    // Title and caption.
    detail::drawText(cr, options.title.empty() ? "Raster image of the colliding pair" : options.title,
                     kRasterLeftMargin, 28, 18, Anchor::Left, true);
    std::ostringstream caption;
    caption.precision(3);
    caption << "seen from +" << axisName(grid.axis) << ", rays along +" << axisName(grid.axis)
            << " (toward the viewer), " << grid.width << " x " << grid.height << " pixels of " << grid.pixel << " m; "
            << hits << " pixel" << (hits == 1 ? "" : "s") << " where Sort_Search_Pair finds the solids overlapping";
    detail::drawText(cr, options.subtitle.empty() ? caption.str() : options.subtitle, kRasterLeftMargin, 50, 12);
    if (!options.subtitle.empty())
        detail::drawText(cr, caption.str(), kRasterLeftMargin, 66, 11);

    // Legend.
    double x = kRasterLeftMargin;
    const double y = layout.top + gridH + 70;
    auto swatch = [&](const Colour &colour, const std::string &text)
    {
        cairo_rectangle(cr, x, y - 10, 16, 12);
        detail::setColour(cr, colour);
        cairo_fill_preserve(cr);
        detail::setColour(cr, kInk);
        cairo_set_line_width(cr, 0.5);
        cairo_stroke(cr);
        detail::drawText(cr, text, x + 22, y, 12);
        x += 22 + detail::textWidth(cr, text, 12) + 18;
    };
    swatch(kComponentOnly, options.componentLabel);
    swatch(kObjectOnly, options.objectLabel);
    swatch(kBoth, "both on the ray");
    swatch(kHit, "collision (hit pixel)");
    detail::setColour(cr, kInk);
    detail::drawText(cr,
                     "Coverage of the candidate triangles after culling (Cai et al., Alg. 1); hit pixels as in Fig. 6.",
                     kRasterLeftMargin, y + 22, 11);
}
}  // namespace

RasterPictureLayout writeRasterPicture(const std::string &pngPath, const RasterImage &image,
                                       const RasterPictureOptions &options)
{
    const RasterPictureLayout layout = checkedLayout(image, options);
    detail::Canvas canvas(layout.width, layout.height);
    paintRasterPicture(canvas, image, layout, options);
    canvas.writePng(pngPath);
    return layout;
}

std::string rasterPicturePng(const RasterImage &image, const RasterPictureOptions &options)
{
    const RasterPictureLayout layout = checkedLayout(image, options);
    detail::Canvas canvas(layout.width, layout.height);
    paintRasterPicture(canvas, image, layout, options);
    return canvas.pngBytes();
}
}  // namespace rastercheck::render
