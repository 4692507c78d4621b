#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "rastercheck/model/RobotModel.h"
#include "rastercheck/model/Scene.h"

namespace rastercheck::render
{
/** \brief Which projection a site picture uses. */
enum class SiteView
{
    /** \brief Plan view: world x to the right, y up; objects shaded by their height. */
    Top,
    /** \brief Elevation: a horizontal direction to the right (by default the direction of the lift,
        from the tracked link's first position to its last), world z up; objects shaded by depth. */
    Side
};

/** \brief "top" or "side"; throws ConfigurationError otherwise. */
SiteView parseSiteView(const std::string &text);

struct SitePictureOptions
{
    SiteView view = SiteView::Top;
    /** \brief Length of the longer side of the plot area (pixels); the world is drawn to scale. */
    int plotSide = 1100;
    /** \brief First line of the picture; empty: "Top view" / "Side view". */
    std::string title;
    /** \brief Second line (problem, planner, ...); may be empty. */
    std::string subtitle;
    /** \brief The link whose origin traces the path line (a crane's load or hook); empty: the last
        link of the model. */
    std::string trackedLink;
    /** \brief Path states drawn as ghosted silhouettes between the first and the last state. */
    int ghosts = 6;
    /** \brief Side view only: the horizontal direction (world xy, any length); zero: along the lift. */
    Eigen::Vector2d sideDirection = Eigen::Vector2d::Zero();
    /** \brief A row of \a states drawn in red as the colliding state, with this label; -1: none. */
    int collidingState = -1;
    std::string collidingLabel = "collision";
};

/** \brief What was drawn, for callers that annotate or test a picture. */
struct SitePictureInfo
{
    int width = 0;   ///< pixels
    int height = 0;  ///< pixels
    double pixelsPerMetre = 0.0;
    /** \brief Screen position (pixels) of world point \a p under this picture's projection. */
    Eigen::Vector2d toScreen(const Eigen::Vector3d &p) const;

    // Projection: screen = origin + pixelsPerMetre * (dot(p, right), -dot(p, up)).
    Eigen::Vector3d right = Eigen::Vector3d::UnitX();
    Eigen::Vector3d up = Eigen::Vector3d::UnitY();
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
};

/** \brief Draws the scene and a robot path into a PNG: every object as the filled union of its
    triangles' projections with its convex outline (painted far to near), the robot at the first
    state ("start", blue) and the last ("goal", green), \a options.ghosts states between them as
    grey silhouettes, the tracked link's trajectory through all states in order (and between them:
    the coordinates move linearly from one state to the next, as a planned path's motions do), axes
    with ticks in metres, a scale bar, object labels and a legend. \a states: rows x
    robot.numCoordinates() values (row-major, the robot's coordinate order). One row draws the robot
    once.
    Throws ConfigurationError on a bad size, an unknown tracked link or an empty drawing, InputError
    when the file cannot be written. */
SitePictureInfo writeSitePicture(const std::string &pngPath, const RobotModel &robot, const Scene &scene,
                                 const std::vector<double> &states, const SitePictureOptions &options = {});
}  // namespace rastercheck::render
