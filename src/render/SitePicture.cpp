#include "render/SitePicture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "rastercheck/core/Error.h"
#include "rastercheck/model/Kinematics.h"
#include "render/Canvas.h"

namespace rastercheck::render
{
using detail::Anchor;
using detail::Colour;
using detail::kInk;

SiteView parseSiteView(const std::string &text)
{
    if (text == "top")
        return SiteView::Top;
    if (text == "side")
        return SiteView::Side;
    throw ConfigurationError("unknown view '" + text + "' (expected top or side)");
}

Eigen::Vector2d SitePictureInfo::toScreen(const Eigen::Vector3d &p) const
{
    return origin + pixelsPerMetre * Eigen::Vector2d(p.dot(right), -p.dot(up));
}

namespace
{
constexpr double kSiteLeftMargin = 70, kSiteRightMargin = 30, kSiteTopMargin = 70, kSiteBottomMargin = 120;
constexpr int kSiteMinimumWidth = 860;

const Colour kPlotBackground{0.975, 0.975, 0.965};
const Colour kGridLine{0.86, 0.86, 0.84};
const Colour kStartColour{0.18, 0.43, 0.72};
const Colour kGoalColour{0.17, 0.55, 0.33};
const Colour kGhostColour{0.45, 0.45, 0.48};
const Colour kCollisionColour{0.84, 0.15, 0.16};
const Colour kPathColour{0.90, 0.47, 0.0};
const Colour kGroundColour{0.55, 0.42, 0.28};

/** \brief One thing to paint: the screen triangles of a solid and the hull for its outline. */
struct Shape
{
    std::vector<Eigen::Vector2d> triangles;  // 3 per triangle, counter-clockwise on screen
    std::vector<Eigen::Vector2d> hull;
    double depth = 0.0;  // larger = nearer the viewer, painted later
    double top = 0.0;    // world z of the highest vertex
};

Shape makeShape(const SitePictureInfo &info, const std::vector<Eigen::Vector3d> &world,
                const std::vector<Mesh::Triangle> &triangles, const Eigen::Vector3d &toward)
{
    Shape shape;
    shape.depth = -std::numeric_limits<double>::infinity();
    shape.top = -std::numeric_limits<double>::infinity();
    std::vector<Eigen::Vector2d> screen(world.size());
    for (std::size_t i = 0; i < world.size(); ++i)
    {
        screen[i] = info.toScreen(world[i]);
        shape.depth = std::max(shape.depth, world[i].dot(toward));
        shape.top = std::max(shape.top, world[i].z());
    }
    shape.triangles.reserve(3 * triangles.size());
    std::vector<Eigen::Vector2d> used;
    for (const Mesh::Triangle &t : triangles)
    {
        const Eigen::Vector2d &a = screen[t[0]], &b = screen[t[1]], &c = screen[t[2]];
        const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
        // A closed surface projects to front and back faces of opposite orientation; giving every
        // triangle the same orientation makes the non-zero fill the union of the projections.
        shape.triangles.push_back(a);
        shape.triangles.push_back(area >= 0 ? b : c);
        shape.triangles.push_back(area >= 0 ? c : b);
        used.insert(used.end(), {a, b, c});
    }
    shape.hull = detail::convexHull(std::move(used));
    return shape;
}

void paintShape(cairo_t *cr, const Shape &shape, const Colour &fill, const Colour &outline, double lineWidth)
{
    for (std::size_t i = 0; i + 2 < shape.triangles.size(); i += 3)
        detail::addPolygon(cr, {shape.triangles[i], shape.triangles[i + 1], shape.triangles[i + 2]});
    cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
    detail::setColour(cr, fill);
    cairo_fill(cr);
    detail::addPolygon(cr, shape.hull);
    detail::setColour(cr, outline);
    cairo_set_line_width(cr, lineWidth);
    cairo_stroke(cr);
}

Colour mix(const Colour &a, const Colour &b, double t)
{
    return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}

/** \brief Text with a white halo, readable over any fill. */
void drawLabel(cairo_t *cr, const std::string &text, double x, double y, double size, Anchor anchor,
               const Colour &colour = kInk)
{
    const double width = detail::textWidth(cr, text, size);
    const double shift = anchor == Anchor::Left ? 0.0 : (anchor == Anchor::Centre ? width / 2 : width);
    cairo_move_to(cr, x - shift, y);
    cairo_text_path(cr, text.c_str());
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
    cairo_set_line_width(cr, 3.0);
    cairo_stroke_preserve(cr);
    detail::setColour(cr, colour);
    cairo_fill(cr);
}

/** \brief "pipe_rack_bent_07" -> "pipe_rack_bent": objects numbered in a series share one label
    when each alone is too small to carry one. */
std::string seriesName(const std::string &id)
{
    std::size_t end = id.size();
    while (end > 0 && std::isdigit(static_cast<unsigned char>(id[end - 1])))
        --end;
    if (end == id.size() || end == 0)
        return id;
    while (end > 0 && (id[end - 1] == '_' || id[end - 1] == '-'))
        --end;
    return end == 0 ? id : id.substr(0, end);
}

std::string metres(double value)
{
    std::ostringstream text;
    text.precision(value < 10 ? 2 : 3);
    text << value << " m";
    return text.str();
}

struct Box2
{
    double x0, y0, x1, y1;
    bool overlaps(const Box2 &o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};

/** \brief Labels the objects (by id; small members of a numbered series by series), skipping
    labels that would cover one already placed (\a placed starts with the path markers' labels). */
void labelObjects(cairo_t *cr, const Scene &scene, const std::vector<Shape> &shapes, const Box2 &plot, bool withHeight,
                  std::vector<Box2> placed)
{
    struct Group
    {
        Box2 box{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
        double top = 0.0;
        int members = 0;
        void add(const Box2 &b, double height)
        {
            box = {std::min(box.x0, b.x0), std::min(box.y0, b.y0), std::max(box.x1, b.x1), std::max(box.y1, b.y1)};
            top = std::max(top, height);
        }
    };
    constexpr double kLabelable = 18.0;  // pixels: the smaller side an object needs to carry its own label
    std::map<std::string, Group> ids;
    for (std::size_t i = 0; i < shapes.size(); ++i)
    {
        const std::string &name = scene.objects[i].name;
        const std::string id = name.substr(0, name.find('/'));
        Box2 b{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
               -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
        for (const Eigen::Vector2d &p : shapes[i].hull)
            b = {std::min(b.x0, p.x()), std::min(b.y0, p.y()), std::max(b.x1, p.x()), std::max(b.y1, p.y())};
        ids[id].add(b, shapes[i].top);
    }
    std::map<std::string, Group> labels;
    for (const auto &[id, group] : ids)
    {
        const bool bigEnough = std::min(group.box.x1 - group.box.x0, group.box.y1 - group.box.y0) >= kLabelable;
        Group &target = labels[bigEnough ? id : seriesName(id)];
        target.add(group.box, group.top);
        target.members += 1;
    }
    std::vector<std::pair<std::string, Group>> ordered(labels.begin(), labels.end());
    std::sort(ordered.begin(), ordered.end(),
              [](const auto &a, const auto &b)
              {
                  const double areaA = (a.second.box.x1 - a.second.box.x0) * (a.second.box.y1 - a.second.box.y0);
                  const double areaB = (b.second.box.x1 - b.second.box.x0) * (b.second.box.y1 - b.second.box.y0);
                  return areaA > areaB;
              });
    constexpr double size = 11.0;
    for (const auto &[name, group] : ordered)
    {
        const Box2 &b = group.box;
        if (std::min(b.x1 - b.x0, b.y1 - b.y0) < kLabelable)
            continue;
        std::string text = group.members > 1 ? name + " \u00d7" + std::to_string(group.members) : name;
        if (withHeight)
            text += " \u00b7 " + metres(group.top);
        const double width = detail::textWidth(cr, text, size);
        const double cx = 0.5 * (b.x0 + b.x1);
        for (double baseline : {0.5 * (b.y0 + b.y1) + size / 2, b.y0 - 4, b.y1 + size + 2})
        {
            const Box2 box{cx - width / 2 - 2, baseline - size, cx + width / 2 + 2, baseline + 3};
            if (box.x0 < plot.x0 || box.x1 > plot.x1 || box.y0 < plot.y0 || box.y1 > plot.y1)
                continue;
            if (std::any_of(placed.begin(), placed.end(), [&](const Box2 &p) { return p.overlaps(box); }))
                continue;
            drawLabel(cr, text, cx, baseline, size, Anchor::Centre);
            placed.push_back(box);
            break;
        }
    }
}

/** \brief The robot's components at one state, as screen shapes in painting order. */
std::vector<Shape> robotShapes(const RobotModel &robot, RobotData &data, const double *q, const SitePictureInfo &info,
                               const Eigen::Vector3d &toward, bool topView)
{
    forwardKinematics(robot, data, q);
    std::vector<Shape> shapes;
    for (const Component &component : robot.components)
    {
        if (component.mesh.empty())
            continue;
        std::vector<Eigen::Vector3d> world(component.mesh.vertices.size());
        const Eigen::Isometry3d &oMl = data.oMl[static_cast<std::size_t>(component.link)];
        for (std::size_t i = 0; i < world.size(); ++i)
            world[i] = oMl * component.mesh.vertices[i];
        shapes.push_back(makeShape(info, world, component.mesh.triangles, toward));
    }
    std::sort(shapes.begin(), shapes.end(),
              [topView](const Shape &a, const Shape &b) { return topView ? a.top < b.top : a.depth < b.depth; });
    return shapes;
}

void paintRobot(cairo_t *cr, const std::vector<Shape> &shapes, const Colour &colour, double alpha)
{
    cairo_push_group(cr);
    for (const Shape &shape : shapes)
        paintShape(cr, shape, mix(colour, {1, 1, 1}, 0.25), mix(colour, {0, 0, 0}, 0.35), 1.0);
    cairo_pop_group_to_source(cr);
    // Painting the group at once keeps overlapping parts of one state from darkening each other.
    cairo_paint_with_alpha(cr, alpha);
}

std::string directionName(const Eigen::Vector3d &v)
{
    static const char *names[3][2] = {{"+x", "-x"}, {"+y", "-y"}, {"+z", "-z"}};
    for (int axis = 0; axis < 3; ++axis)
        if (std::abs(std::abs(v[axis]) - 1.0) < 1e-9)
            return names[axis][v[axis] > 0 ? 0 : 1];
    std::ostringstream text;
    text.precision(2);
    text << std::fixed << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return text.str();
}
}  // namespace

SitePictureInfo writeSitePicture(const std::string &pngPath, const RobotModel &robot, const Scene &scene,
                                 const std::vector<double> &states, const SitePictureOptions &options)
{
    const std::size_t dof = robot.numCoordinates();
    if (dof == 0 || states.empty() || states.size() % dof != 0)
        throw ConfigurationError("site picture: " + std::to_string(states.size()) +
                                 " values are not a whole number of states of " + std::to_string(dof) + " coordinates");
    const std::size_t rows = states.size() / dof;
    const int tracked =
        options.trackedLink.empty() ? static_cast<int>(robot.links.size()) - 1 : robot.linkIndex(options.trackedLink);
    if (tracked < 0)
        throw ConfigurationError("site picture: the robot has no link '" + options.trackedLink + "'");
    if (options.collidingState >= static_cast<int>(rows))
        throw ConfigurationError("site picture: colliding state " + std::to_string(options.collidingState) +
                                 " is not one of the " + std::to_string(rows) + " states");
    const bool top = options.view == SiteView::Top;

    // The tracked link's trajectory through every state and between them: a planner's path has few
    // states, and the link moves on a curve between two of them (the coordinates move linearly, as
    // the path's motions do), not on the chord.
    constexpr int kTraceSteps = 24;
    RobotData data(robot);
    std::vector<Eigen::Vector3d> trace;
    trace.reserve((rows - 1) * kTraceSteps + 1);
    std::vector<double> q(dof);
    for (std::size_t r = 0; r < rows; ++r)
        for (int k = 0; k < (r + 1 < rows ? kTraceSteps : 1); ++k)
        {
            const double t = static_cast<double>(k) / kTraceSteps;
            for (std::size_t d = 0; d < dof; ++d)
                q[d] = k == 0 ? states[r * dof + d] : (1 - t) * states[r * dof + d] + t * states[(r + 1) * dof + d];
            forwardKinematics(robot, data, q.data());
            trace.push_back(data.oMl[static_cast<std::size_t>(tracked)].translation());
        }

    SitePictureInfo info;
    if (top)
    {
        info.right = Eigen::Vector3d::UnitX();
        info.up = Eigen::Vector3d::UnitY();
    }
    else
    {
        Eigen::Vector2d direction = options.sideDirection;
        if (direction.norm() < 1e-12)
            direction = (trace.back() - trace.front()).head<2>();
        if (direction.norm() < 1e-6)
            direction = Eigen::Vector2d::UnitX();
        direction.normalize();
        info.right = Eigen::Vector3d(direction.x(), direction.y(), 0.0);
        info.up = Eigen::Vector3d::UnitZ();
    }
    const Eigen::Vector3d toward = info.right.cross(info.up);

    // The drawn states: ghosts spread evenly between the first and the last row.
    std::vector<std::size_t> ghostRows;
    if (rows > 2)
        for (int k = 1; k <= options.ghosts; ++k)
        {
            const auto row = static_cast<std::size_t>(
                std::lround(static_cast<double>(k) * static_cast<double>(rows - 1) / (options.ghosts + 1)));
            if (row > 0 && row + 1 < rows && (ghostRows.empty() || ghostRows.back() != row))
                ghostRows.push_back(row);
        }
    std::vector<std::size_t> robotRows = ghostRows;
    robotRows.push_back(0);
    robotRows.push_back(rows - 1);
    if (options.collidingState >= 0)
        robotRows.push_back(static_cast<std::size_t>(options.collidingState));

    // Extent of everything drawn, in (right, up) coordinates.
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d hi = -lo;
    auto extend = [&](const Eigen::Vector3d &p)
    {
        const Eigen::Vector2d q(p.dot(info.right), p.dot(info.up));
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    };
    for (const SceneObject &object : scene.objects)
        for (const Eigen::Vector3d &v : object.mesh.vertices)
            extend(v);
    for (std::size_t row : robotRows)
    {
        forwardKinematics(robot, data, states.data() + row * dof);
        for (const Component &component : robot.components)
            for (const Eigen::Vector3d &v : component.mesh.vertices)
                extend(data.oMl[static_cast<std::size_t>(component.link)] * v);
    }
    for (const Eigen::Vector3d &p : trace)
        extend(p);
    if (!top)
        lo.y() = std::min(lo.y(), 0.0);
    if (!(lo.array() <= hi.array()).all())
        throw ConfigurationError("site picture: nothing to draw");
    const Eigen::Vector2d pad = 0.04 * (hi - lo).cwiseMax(Eigen::Vector2d::Constant((hi - lo).maxCoeff()));
    lo -= pad;
    hi += pad;
    if (!top)
        lo.y() = std::max(lo.y(), std::min(0.0, lo.y() + pad.y()) - 0.02 * (hi.y() - lo.y()));

    const double scale = options.plotSide / std::max(1e-9, (hi - lo).maxCoeff());
    const double plotWidth = (hi.x() - lo.x()) * scale, plotHeight = (hi.y() - lo.y()) * scale;
    info.pixelsPerMetre = scale;
    info.width =
        std::max(kSiteMinimumWidth, static_cast<int>(std::ceil(kSiteLeftMargin + plotWidth + kSiteRightMargin)));
    info.height = static_cast<int>(std::ceil(kSiteTopMargin + plotHeight + kSiteBottomMargin));
    info.origin = Eigen::Vector2d(kSiteLeftMargin - lo.x() * scale, kSiteTopMargin + hi.y() * scale);
    const Box2 plot{kSiteLeftMargin, kSiteTopMargin, kSiteLeftMargin + plotWidth, kSiteTopMargin + plotHeight};

    detail::Canvas canvas(info.width, info.height);
    cairo_t *cr = canvas.context();

    // Plot area and grid.
    cairo_rectangle(cr, plot.x0, plot.y0, plotWidth, plotHeight);
    detail::setColour(cr, kPlotBackground);
    cairo_fill(cr);
    const double step = detail::niceStep(std::max(hi.x() - lo.x(), hi.y() - lo.y()), 8);
    cairo_set_line_width(cr, 1.0);
    for (double x = std::ceil(lo.x() / step) * step; x <= hi.x(); x += step)
    {
        const double sx = info.origin.x() + x * scale;
        detail::setColour(cr, kGridLine);
        cairo_move_to(cr, sx, plot.y0);
        cairo_line_to(cr, sx, plot.y1);
        cairo_stroke(cr);
        detail::setColour(cr, kInk);
        detail::drawText(cr, detail::formatTick(x, step), sx, plot.y1 + 16, 11, Anchor::Centre);
    }
    for (double y = std::ceil(lo.y() / step) * step; y <= hi.y(); y += step)
    {
        const double sy = info.origin.y() - y * scale;
        detail::setColour(cr, kGridLine);
        cairo_move_to(cr, plot.x0, sy);
        cairo_line_to(cr, plot.x1, sy);
        cairo_stroke(cr);
        detail::setColour(cr, kInk);
        detail::drawText(cr, detail::formatTick(y, step), plot.x0 - 6, sy + 4, 11, Anchor::Right);
    }
    if (!top)
    {
        const double ground = info.origin.y();
        cairo_rectangle(cr, plot.x0, ground, plotWidth, plot.y1 - ground);
        detail::setColour(cr, mix(kGroundColour, {1, 1, 1}, 0.75));
        cairo_fill(cr);
        cairo_move_to(cr, plot.x0, ground);
        cairo_line_to(cr, plot.x1, ground);
        detail::setColour(cr, kGroundColour);
        cairo_set_line_width(cr, 2.0);
        cairo_stroke(cr);
    }

    // Objects, far to near (top view: low to high), shaded by height or depth.
    std::vector<Shape> objectShapes;
    objectShapes.reserve(scene.objects.size());
    double highest = 1e-9, nearest = -std::numeric_limits<double>::infinity(),
           farthest = std::numeric_limits<double>::infinity();
    for (const SceneObject &object : scene.objects)
    {
        objectShapes.push_back(makeShape(info, object.mesh.vertices, object.mesh.triangles, toward));
        highest = std::max(highest, objectShapes.back().top);
        nearest = std::max(nearest, objectShapes.back().depth);
        farthest = std::min(farthest, objectShapes.back().depth);
    }
    std::vector<std::size_t> order(objectShapes.size());
    for (std::size_t i = 0; i < order.size(); ++i)
        order[i] = i;
    std::sort(
        order.begin(), order.end(),
        [&](std::size_t a, std::size_t b)
        { return top ? objectShapes[a].top < objectShapes[b].top : objectShapes[a].depth < objectShapes[b].depth; });
    const Colour lowObject{0.86, 0.87, 0.89}, highObject{0.36, 0.41, 0.47};
    for (std::size_t i : order)
    {
        const Shape &shape = objectShapes[i];
        const double t = top ? std::clamp(shape.top / highest, 0.0, 1.0)
                             : (nearest > farthest ? (shape.depth - farthest) / (nearest - farthest) : 1.0);
        const Colour fill = mix(lowObject, highObject, 0.15 + 0.85 * t);
        paintShape(cr, shape, fill, mix(fill, {0, 0, 0}, 0.45), 1.0);
    }

    // The robot: ghosts, then start and goal, then the colliding state on top.
    for (std::size_t row : ghostRows)
        paintRobot(cr, robotShapes(robot, data, states.data() + row * dof, info, toward, top), kGhostColour, 0.35);
    paintRobot(cr, robotShapes(robot, data, states.data(), info, toward, top), kStartColour, 0.9);
    if (rows > 1)
        paintRobot(cr, robotShapes(robot, data, states.data() + (rows - 1) * dof, info, toward, top), kGoalColour, 0.9);
    if (options.collidingState >= 0)
        paintRobot(cr,
                   robotShapes(robot, data, states.data() + static_cast<std::size_t>(options.collidingState) * dof,
                               info, toward, top),
                   kCollisionColour, 0.9);

    // The tracked link's trajectory.
    if (rows > 1)
    {
        const Eigen::Vector2d first = info.toScreen(trace.front());
        cairo_move_to(cr, first.x(), first.y());
        for (const Eigen::Vector3d &p : trace)
        {
            const Eigen::Vector2d s = info.toScreen(p);
            cairo_line_to(cr, s.x(), s.y());
        }
        cairo_set_source_rgba(cr, 1, 1, 1, 0.8);
        cairo_set_line_width(cr, 5.0);
        cairo_stroke_preserve(cr);
        detail::setColour(cr, kPathColour);
        cairo_set_line_width(cr, 2.5);
        cairo_stroke(cr);
    }
    std::vector<Box2> markerLabels;
    auto marker = [&](const Eigen::Vector3d &p, const Colour &colour, const std::string &text)
    {
        const Eigen::Vector2d s = info.toScreen(p);
        markerLabels.push_back({s.x() - 6, s.y() - 20, s.x() + 12 + detail::textWidth(cr, text, 13), s.y() + 6});
        cairo_arc(cr, s.x(), s.y(), 5.0, 0, 2 * M_PI);
        detail::setColour(cr, colour);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, 1, 1, 1);
        cairo_set_line_width(cr, 1.5);
        cairo_stroke(cr);
        drawLabel(cr, text, s.x() + 9, s.y() - 7, 13, Anchor::Left, mix(colour, {0, 0, 0}, 0.3));
    };
    marker(trace.front(), kStartColour, "start");
    if (rows > 1)
        marker(trace.back(), kGoalColour, "goal");
    if (options.collidingState >= 0)
        marker(trace[static_cast<std::size_t>(options.collidingState) * kTraceSteps], kCollisionColour,
               options.collidingLabel);

    labelObjects(cr, scene, objectShapes, plot, top, markerLabels);

    // Frame, axis names, orientation note.
    cairo_rectangle(cr, plot.x0, plot.y0, plotWidth, plotHeight);
    detail::setColour(cr, kInk);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
    const std::string horizontal = top ? "x (m)" : "distance along " + directionName(info.right) + " (m)";
    detail::drawText(cr, horizontal, 0.5 * (plot.x0 + plot.x1), plot.y1 + 34, 12, Anchor::Centre);
    cairo_save(cr);
    cairo_translate(cr, 18, 0.5 * (plot.y0 + plot.y1));
    cairo_rotate(cr, -M_PI / 2);
    detail::drawText(cr, top ? "y (m)" : "z (m)", 0, 0, 12, Anchor::Centre);
    cairo_restore(cr);
    drawLabel(cr, top ? "seen from above (+z)" : "seen from " + directionName(toward), plot.x1 - 8, plot.y0 + 18, 12,
              Anchor::Right);

    // Title.
    const std::string title = options.title.empty() ? (top ? "Top view" : "Side view") : options.title;
    detail::setColour(cr, kInk);
    detail::drawText(cr, title, kSiteLeftMargin, 28, 18, Anchor::Left, true);
    if (!options.subtitle.empty())
        detail::drawText(cr, options.subtitle, kSiteLeftMargin, 50, 12, Anchor::Left);

    // Scale bar, then the legend, along the bottom.
    const double barMetres = detail::niceStep(hi.x() - lo.x(), 5);
    const double barPixels = barMetres * scale, barY = plot.y1 + 62;
    for (int half = 0; half < 2; ++half)
    {
        cairo_rectangle(cr, kSiteLeftMargin + half * barPixels / 2, barY, barPixels / 2, 7);
        detail::setColour(cr, half == 0 ? kInk : Colour{1, 1, 1});
        cairo_fill_preserve(cr);
        detail::setColour(cr, kInk);
        cairo_set_line_width(cr, 1.0);
        cairo_stroke(cr);
    }
    detail::drawText(cr, "0", kSiteLeftMargin, barY + 22, 11, Anchor::Centre);
    detail::drawText(cr, detail::formatTick(barMetres, barMetres) + " m", kSiteLeftMargin + barPixels, barY + 22, 11,
                     Anchor::Centre);

    double x = kSiteLeftMargin + std::max(barPixels, 40.0) + 40;
    const double legendY = barY + 8;
    auto swatch = [&](const Colour &colour, double alpha, const std::string &text)
    {
        cairo_rectangle(cr, x, legendY - 10, 16, 12);
        detail::setColour(cr, colour, alpha);
        cairo_fill(cr);
        detail::setColour(cr, kInk);
        detail::drawText(cr, text, x + 22, legendY, 12);
        x += 22 + detail::textWidth(cr, text, 12) + 18;
    };
    swatch(kStartColour, 0.9, "start");
    if (rows > 1)
        swatch(kGoalColour, 0.9, "goal");
    if (!ghostRows.empty())
        swatch(kGhostColour, 0.35, "path states");
    if (options.collidingState >= 0)
        swatch(kCollisionColour, 0.9, options.collidingLabel);
    if (rows > 1)
    {
        cairo_move_to(cr, x, legendY - 4);
        cairo_line_to(cr, x + 16, legendY - 4);
        detail::setColour(cr, kPathColour);
        cairo_set_line_width(cr, 2.5);
        cairo_stroke(cr);
        detail::setColour(cr, kInk);
        const std::string text = "path of " + robot.links[static_cast<std::size_t>(tracked)].name;
        detail::drawText(cr, text, x + 22, legendY, 12);
        x += 22 + detail::textWidth(cr, text, 12) + 18;
    }
    cairo_rectangle(cr, x, legendY - 10, 16, 12);
    cairo_pattern_t *ramp = cairo_pattern_create_linear(x, 0, x + 16, 0);
    cairo_pattern_add_color_stop_rgb(ramp, 0, lowObject.r, lowObject.g, lowObject.b);
    cairo_pattern_add_color_stop_rgb(ramp, 1, highObject.r, highObject.g, highObject.b);
    cairo_set_source(cr, ramp);
    cairo_fill(cr);
    cairo_pattern_destroy(ramp);
    detail::setColour(cr, kInk);
    detail::drawText(cr, top ? "objects (darker = taller)" : "objects (darker = nearer)", x + 22, legendY, 12);

    canvas.writePng(pngPath);
    return info;
}
}  // namespace rastercheck::render
