#pragma once
// Internal to rastercheck_render: the Cairo surface and the drawing helpers the pictures share.
// Public render headers do not include this file, so Cairo stays out of every user's interface.

#include <string>
#include <vector>

#include <cairo.h>
#include <Eigen/Core>

namespace rastercheck::render::detail
{
/** \brief An RGB colour, components in [0, 1]. */
struct Colour
{
    double r, g, b;
};

/** \brief The pictures' text, axes and outlines. */
inline const Colour kInk{0.15, 0.15, 0.17};

/** \brief An ARGB image surface and its context; owns both. */
class Canvas
{
public:
    /** \brief A white \a width x \a height pixel image. */
    Canvas(int width, int height);
    ~Canvas();
    Canvas(const Canvas &) = delete;
    Canvas &operator=(const Canvas &) = delete;

    cairo_t *context() const { return cr_; }
    int width() const { return width_; }
    int height() const { return height_; }

    /** \brief Writes the image as PNG; throws InputError naming \a path when Cairo cannot. */
    void writePng(const std::string &path) const;
    /** \brief The image as the bytes of a PNG file. */
    std::string pngBytes() const;

private:
    int width_;
    int height_;
    cairo_surface_t *surface_;
    cairo_t *cr_;
};

void setColour(cairo_t *cr, const Colour &colour, double alpha = 1.0);

/** \brief Where a text's anchor point sits relative to the text. */
enum class Anchor
{
    Left,
    Centre,
    Right
};

/** \brief Draws \a text with its baseline at y and its left edge, centre or right edge at x. */
void drawText(cairo_t *cr, const std::string &text, double x, double y, double size, Anchor anchor = Anchor::Left,
              bool bold = false);

/** \brief Width of \a text at \a size (pixels). */
double textWidth(cairo_t *cr, const std::string &text, double size, bool bold = false);

/** \brief A round step (1, 2 or 5 times a power of ten) close to \a range / \a count. */
double niceStep(double range, int count);

/** \brief A number for an axis label: no trailing zeros, at most the decimals \a step needs. */
std::string formatTick(double value, double step);

/** \brief Convex hull of 2-D points, counter-clockwise (Andrew's monotone chain); fewer than three
    distinct points give what there is. */
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points);

/** \brief Adds the closed polygon \a points to the current path. */
void addPolygon(cairo_t *cr, const std::vector<Eigen::Vector2d> &points);
}  // namespace rastercheck::render::detail
