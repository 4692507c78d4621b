// The render module: PNG files of the expected size, pixels where the layout says they are, and
// `rastercheck render` end to end.
#include <sys/wait.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <cairo.h>
#include <gtest/gtest.h>

#include "TestSupport.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/io/Problem.h"
#include "render/RasterPicture.h"
#include "render/SitePicture.h"

namespace rc = rastercheck;

namespace
{
/** \brief A PNG read back: size and the colour of any pixel. */
class Png
{
public:
    explicit Png(const std::string &path) : surface_(cairo_image_surface_create_from_png(path.c_str())) {}
    ~Png() { cairo_surface_destroy(surface_); }
    Png(const Png &) = delete;
    Png &operator=(const Png &) = delete;

    bool ok() const { return cairo_surface_status(surface_) == CAIRO_STATUS_SUCCESS; }
    int width() const { return cairo_image_surface_get_width(surface_); }
    int height() const { return cairo_image_surface_get_height(surface_); }
    /** \brief (r, g, b), 0..255, of the pixel containing screen point (x, y). */
    std::array<int, 3> rgb(double x, double y) const
    {
        const auto *row = cairo_image_surface_get_data(surface_) +
                          static_cast<std::ptrdiff_t>(y) * cairo_image_surface_get_stride(surface_);
        std::uint32_t argb;
        std::memcpy(&argb, row + 4 * static_cast<std::ptrdiff_t>(x), 4);
        return {static_cast<int>((argb >> 16) & 0xff), static_cast<int>((argb >> 8) & 0xff),
                static_cast<int>(argb & 0xff)};
    }

private:
    cairo_surface_t *surface_;
};

bool isRed(const std::array<int, 3> &c)
{
    return c[0] > 200 && c[1] < 50 && c[2] < 50;
}

rc::RasterImage knownImage()
{
    rc::RasterImage image;
    image.grid.axis = 0;  // rays along x; u = y, v = z
    image.grid.origin[0] = 1.0f;
    image.grid.origin[1] = 2.0f;
    image.grid.pixel = 0.1f;
    image.grid.width = 8;
    image.grid.height = 5;
    image.coverage.assign(40, 0);
    image.hits.assign(40, 0);
    for (int i = 2; i < 8; ++i)
        for (int j = 0; j < 3; ++j)
            image.coverage[static_cast<std::size_t>(j * 8 + i)] = i < 4 ? 1 : 3;
    image.coverage[4 * 8 + 0] = 2;
    image.hits[1 * 8 + 6] = 1;  // column 6, row 1
    return image;
}

using rastercheck::test::plant;

/** \brief Start and goal of the plant lift, with \a between states linearly between them. */
std::vector<double> liftStates(int between)
{
    const rc::MotionPlanRequest request = rc::loadMoveItRequest(rc::test::sourcePath("robots/sites/plant_lift.yaml"));
    const rc::RobotModel &robot = *plant().robot;
    std::vector<double> states;
    for (int k = 0; k <= between + 1; ++k)
    {
        const double t = static_cast<double>(k) / (between + 1);
        for (const std::string &name : robot.coordinateNames)
            states.push_back((1 - t) * request.startJoints.at(name) + t * request.goalJoints.at(name));
    }
    return states;
}

std::string runCli(const std::string &arguments, int &status)
{
    const rc::test::CommandRun run = rc::test::runCli(arguments);
    status = run.status;
    return run.output;
}
}  // namespace

TEST(RasterPicture, HitPixelIsRedWhereTheLayoutPutsIt)
{
    const std::string dir = rc::test::makeTempDir("render_raster");
    const std::string path = dir + "/raster.png";
    rc::render::RasterPictureOptions options;
    options.gridSide = 400;
    const rc::render::RasterPictureLayout layout = rc::render::writeRasterPicture(path, knownImage(), options);
    EXPECT_EQ(layout.cell, 50);  // 400 / 8 columns
    EXPECT_EQ(layout.gridWidth, 8);
    EXPECT_EQ(layout.gridHeight, 5);

    const Png png(path);
    ASSERT_TRUE(png.ok());
    EXPECT_GT(std::filesystem::file_size(path), 1000u);
    EXPECT_EQ(png.width(), layout.width);
    EXPECT_EQ(png.height(), layout.height);
    EXPECT_GE(png.width(), layout.left + 8 * 50);
    EXPECT_GE(png.height(), layout.top + 5 * 50);

    const Eigen::Vector2d hit = layout.cellCentre(6, 1);
    EXPECT_TRUE(isRed(png.rgb(hit.x(), hit.y())));
    // Rows grow upwards: row 1 is the second row from the bottom of the grid.
    EXPECT_NEAR(hit.y(), layout.top + 3.5 * 50, 1e-9);
    EXPECT_NEAR(hit.x(), layout.left + 6.5 * 50, 1e-9);
    int red = 0;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 8; ++i)
        {
            const Eigen::Vector2d c = layout.cellCentre(i, j);
            red += isRed(png.rgb(c.x(), c.y())) ? 1 : 0;
        }
    EXPECT_EQ(red, 1);
    // Three coverage colours and the empty background are all different.
    const auto component = png.rgb(layout.cellCentre(2, 0).x(), layout.cellCentre(2, 0).y());
    const auto both = png.rgb(layout.cellCentre(5, 0).x(), layout.cellCentre(5, 0).y());
    const auto object = png.rgb(layout.cellCentre(0, 4).x(), layout.cellCentre(0, 4).y());
    const auto empty = png.rgb(layout.cellCentre(0, 0).x(), layout.cellCentre(0, 0).y());
    EXPECT_NE(component, both);
    EXPECT_NE(component, object);
    EXPECT_NE(object, both);
    EXPECT_NE(empty, component);
    EXPECT_NE(empty, object);
}

TEST(RasterPicture, RejectsAnImageThatDoesNotMatchItsGrid)
{
    rc::RasterImage image = knownImage();
    image.hits.pop_back();
    EXPECT_THROW(rc::render::writeRasterPicture(rc::test::makeTempDir("render_bad") + "/x.png", image),
                 rc::ConfigurationError);
    EXPECT_THROW(rc::render::writeRasterPicture("/nonexistent-folder/raster.png", knownImage()), rc::InputError);
}

TEST(SitePicture, TopAndSideViewsOfTheLift)
{
    const std::string dir = rc::test::makeTempDir("render_site");
    const std::vector<double> states = liftStates(20);
    for (const rc::render::SiteView view : {rc::render::SiteView::Top, rc::render::SiteView::Side})
    {
        rc::render::SitePictureOptions options;
        options.view = view;
        options.plotSide = 600;
        options.trackedLink = "load";
        const std::string path = dir + (view == rc::render::SiteView::Top ? "/top.png" : "/side.png");
        const rc::render::SitePictureInfo info =
            rc::render::writeSitePicture(path, *plant().robot, *plant().scene, states, options);
        const Png png(path);
        ASSERT_TRUE(png.ok());
        EXPECT_GT(std::filesystem::file_size(path), 10000u);
        EXPECT_EQ(png.width(), info.width);
        EXPECT_EQ(png.height(), info.height);
        // The longer side of the plot is plotSide pixels: the site is 72 m (pipe rack) to 80 m wide,
        // plus the 4 % margins.
        EXPECT_GT(info.pixelsPerMetre, 600.0 / 100.0);
        EXPECT_LT(info.pixelsPerMetre, 600.0 / 70.0);
        EXPECT_LE(info.width, 860);  // the minimum width, which leaves room for the legend

        // tank_1 (22, -8), 14 m tall, is painted as an object: grey-blue, neither white nor a robot colour.
        if (view == rc::render::SiteView::Top)
        {
            const Eigen::Vector2d tank = info.toScreen({24.0, -4.0, 14.0});
            const auto colour = png.rgb(tank.x(), tank.y());
            EXPECT_LT(colour[0], 220);
            EXPECT_NEAR(colour[0], colour[2], 40);
            // The screen mapping: x to the right, y up.
            EXPECT_GT(info.toScreen({1, 0, 0}).x(), info.toScreen({0, 0, 0}).x());
            EXPECT_LT(info.toScreen({0, 1, 0}).y(), info.toScreen({0, 0, 0}).y());
        }
        else
        {
            // Along the lift (pick at y = -17, set-down at y = +27): y to the right, z up.
            EXPECT_NEAR(info.right.y(), 1.0, 1e-6);
            EXPECT_LT(info.toScreen({0, 0, 1}).y(), info.toScreen({0, 0, 0}).y());
        }
    }
}

TEST(SitePicture, RejectsBadInput)
{
    const std::string dir = rc::test::makeTempDir("render_site_bad");
    std::vector<double> states = liftStates(0);
    states.pop_back();
    EXPECT_THROW(rc::render::writeSitePicture(dir + "/a.png", *plant().robot, *plant().scene, states),
                 rc::ConfigurationError);
    rc::render::SitePictureOptions options;
    options.trackedLink = "jib";
    EXPECT_THROW(rc::render::writeSitePicture(dir + "/b.png", *plant().robot, *plant().scene, liftStates(0), options),
                 rc::ConfigurationError);
    EXPECT_THROW(rc::render::parseSiteView("front"), rc::ConfigurationError);
}

TEST(RenderCli, RequestStraightLineHitsTank1)
{
    const std::string dir = rc::test::makeTempDir("render_cli");
    int status = -1;
    const std::string output =
        runCli("render --robot " + rc::test::sourcePath("robots/crane/crane.urdf") + " --srdf " +
                   rc::test::sourcePath("robots/crane/crane.srdf") + " --scene " +
                   rc::test::sourcePath("robots/sites/plant.yaml") + " --request " +
                   rc::test::sourcePath("robots/sites/plant_lift.yaml") + " --interpolate 49 --out-dir " + dir,
               status);
    ASSERT_EQ(status, 0) << output;
    EXPECT_NE(output.find("first colliding state: row"), std::string::npos) << output;
    EXPECT_NE(output.find("load vs object 'tank_1'"), std::string::npos) << output;
    for (const char *name : {"top.png", "side.png", "raster.png"})
    {
        EXPECT_TRUE(std::filesystem::exists(dir + "/" + name)) << name;
        EXPECT_TRUE(Png(dir + "/" + name).ok()) << name;
    }
}

TEST(RenderCli, ARequestMeansWhatPlanAndViewMakeOfIt)
{
    // The lift's request without the base joints (their neutral value is the request's 0) and
    // with a start joint the crane lacks: the coordinates `plan` and `view` make of it (StateMapping:
    // unnamed coordinates neutral, unknown start joints skipped), so the same first collision.
    const std::string dir = rc::test::makeTempDir("render_cli_request");
    const std::string partial = rc::test::writeFile(dir + "/partial.yaml", R"(start_state:
  joint_state:
    name: [slew, luff, telescope_1, hoist, outrigger]
    position: [-1.570796326795, 0.834431313317, 5, 15.800257730247, 0]
goal_constraints:
  - joint_constraints:
      - joint_name: slew
        position: 1.570796326795
      - joint_name: luff
        position: 0.71942438464
      - joint_name: telescope_1
        position: 8.5
      - joint_name: hoist
        position: 20.933726302844
)");
    auto firstCollision = [&](const std::string &request)
    {
        int status = -1;
        const std::string output =
            runCli("render --robot " + rc::test::sourcePath("robots/crane/crane.urdf") + " --srdf " +
                       rc::test::sourcePath("robots/crane/crane.srdf") + " --scene " +
                       rc::test::sourcePath("robots/sites/plant.yaml") + " --request " + request +
                       " --interpolate 49 --view raster --out-dir " + dir,
                   status);
        EXPECT_EQ(status, 0) << output;
        const std::size_t line = output.find("first colliding state: row");
        return line == std::string::npos ? output : output.substr(line, output.find('\n', line) - line);
    };
    const std::string full = firstCollision(rc::test::sourcePath("robots/sites/plant_lift.yaml"));
    EXPECT_NE(full.find("load vs object 'tank_1'"), std::string::npos) << full;
    EXPECT_EQ(firstCollision(partial), full);
}

TEST(RenderCli, ValidPathHasNoRasterPicture)
{
    const std::string dir = rc::test::makeTempDir("render_cli_valid");
    const std::string csv = rc::test::writeFile(dir + "/states.csv",
                                                "base_x,base_y,base_yaw,slew,luff,telescope_1,hoist\n"
                                                "0,0,0,-1.570796326795,0.834431313317,5,15.800257730247\n"
                                                "0,0,0,-1.570796326795,0.834431313317,5,10\n");
    int status = -1;
    // Without the SRDF the nested boom sections would collide with each other.
    const std::string output = runCli("render --robot " + rc::test::sourcePath("robots/crane/crane.urdf") + " --srdf " +
                                          rc::test::sourcePath("robots/crane/crane.srdf") + " --scene " +
                                          rc::test::sourcePath("robots/sites/plant.yaml") + " --states " + csv +
                                          " --view raster --out-dir " + dir,
                                      status);
    ASSERT_EQ(status, 0) << output;
    EXPECT_NE(output.find("no state collides (2 checked"), std::string::npos) << output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/raster.png"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/top.png"));

    const std::string both = runCli("render --robot x.urdf --states a.csv --request b.yaml --out-dir " + dir, status);
    EXPECT_NE(status, 0);
}
