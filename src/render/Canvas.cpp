#include "render/Canvas.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "rastercheck/core/Error.h"

namespace rastercheck::render::detail
{
Canvas::Canvas(int width, int height)
    : width_(width),
      height_(height),
      surface_(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height)),
      cr_(cairo_create(surface_))
{
    if (cairo_surface_status(surface_) != CAIRO_STATUS_SUCCESS)
        throw ConfigurationError("cannot create a " + std::to_string(width) + " x " + std::to_string(height) +
                                 " image: " + cairo_status_to_string(cairo_surface_status(surface_)));
    cairo_set_source_rgb(cr_, 1.0, 1.0, 1.0);
    cairo_paint(cr_);
    cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
    cairo_set_line_cap(cr_, CAIRO_LINE_CAP_ROUND);
}

Canvas::~Canvas()
{
    cairo_destroy(cr_);
    cairo_surface_destroy(surface_);
}

void Canvas::writePng(const std::string &path) const
{
    cairo_surface_flush(surface_);
    const cairo_status_t status = cairo_surface_write_to_png(surface_, path.c_str());
    if (status != CAIRO_STATUS_SUCCESS)
        throw InputError(path, "", std::string("cannot write the PNG: ") + cairo_status_to_string(status));
}

std::string Canvas::pngBytes() const
{
    cairo_surface_flush(surface_);
    std::string bytes;
    const cairo_write_func_t append = [](void *closure, const unsigned char *data, unsigned int length)
    {
        static_cast<std::string *>(closure)->append(reinterpret_cast<const char *>(data), length);
        return CAIRO_STATUS_SUCCESS;
    };
    const cairo_status_t status = cairo_surface_write_to_png_stream(surface_, append, &bytes);
    if (status != CAIRO_STATUS_SUCCESS)
        throw ConfigurationError(std::string("cannot encode the PNG: ") + cairo_status_to_string(status));
    return bytes;
}

void setColour(cairo_t *cr, const Colour &colour, double alpha)
{
    cairo_set_source_rgba(cr, colour.r, colour.g, colour.b, alpha);
}

namespace
{
void selectFont(cairo_t *cr, double size, bool bold)
{
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}
}  // namespace

double textWidth(cairo_t *cr, const std::string &text, double size, bool bold)
{
    selectFont(cr, size, bold);
    cairo_text_extents_t extents;
    cairo_text_extents(cr, text.c_str(), &extents);
    return extents.x_advance;
}

void drawText(cairo_t *cr, const std::string &text, double x, double y, double size, Anchor anchor, bool bold)
{
    const double width = textWidth(cr, text, size, bold);
    const double shift = anchor == Anchor::Left ? 0.0 : (anchor == Anchor::Centre ? width / 2 : width);
    cairo_move_to(cr, x - shift, y);
    cairo_show_text(cr, text.c_str());
    cairo_new_path(cr);
}

double niceStep(double range, int count)
{
    if (!(range > 0) || count < 1)
        return 1.0;
    const double raw = range / count;
    const double power = std::pow(10.0, std::floor(std::log10(raw)));
    const double fraction = raw / power;
    const double nice = fraction < 1.5 ? 1.0 : (fraction < 3.5 ? 2.0 : (fraction < 7.5 ? 5.0 : 10.0));
    return nice * power;
}

std::string formatTick(double value, double step)
{
    const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
    std::ostringstream text;
    text << std::fixed << std::setprecision(decimals) << (std::abs(value) < step * 1e-6 ? 0.0 : value);
    return text.str();
}

std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points)
{
    std::sort(points.begin(), points.end(),
              [](const Eigen::Vector2d &a, const Eigen::Vector2d &b)
              { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3)
        return points;
    auto cross = [](const Eigen::Vector2d &o, const Eigen::Vector2d &a, const Eigen::Vector2d &b)
    { return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x()); };
    std::vector<Eigen::Vector2d> hull(2 * points.size());
    std::size_t k = 0;
    for (const Eigen::Vector2d &p : points)
    {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0)
            --k;
        hull[k++] = p;
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;)
    {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0)
            --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    return hull;
}

void addPolygon(cairo_t *cr, const std::vector<Eigen::Vector2d> &points)
{
    if (points.empty())
        return;
    cairo_move_to(cr, points[0].x(), points[0].y());
    for (std::size_t i = 1; i < points.size(); ++i)
        cairo_line_to(cr, points[i].x(), points[i].y());
    cairo_close_path(cr);
}
}  // namespace rastercheck::render::detail
