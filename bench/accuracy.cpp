// Accuracy of every mode against the exact oracle (brute force over all pairs, no culls) and FCL:
// false negatives (a colliding state called valid) and false positives, per mode and pixel size,
// on the Panda MotionBenchMaker scenarios and on the blind-spot suites. Writes the tables of
// docs/accuracy.md to stdout.
//
// usage: rastercheck_bench_accuracy [scenes_per_scenario=2] [states_per_scene=1000] [states_per_blind_spot=2000]
#include <cstdio>
#include <cstdlib>

#include "BenchSupport.h"
#include "BlindSpots.h"
#include "Reference.h"
#include "rastercheck/collision/Checker.h"

using namespace rastercheck;

namespace
{
struct Setting
{
    std::string label;
    CollisionMode mode;
    double pixelScale;  // multiple of the model's default pixel
};

const std::vector<Setting> &settings()
{
    static const std::vector<Setting> list{{"exact", CollisionMode::Exact, 1},
                                           {"safe (default)", CollisionMode::Safe, 1},
                                           {"safe, pixel x4", CollisionMode::Safe, 4},
                                           {"raster, pixel x0.5", CollisionMode::Raster, 0.5},
                                           {"raster, pixel x1", CollisionMode::Raster, 1},
                                           {"raster, pixel x4", CollisionMode::Raster, 4},
                                           {"raster, pixel x16", CollisionMode::Raster, 16},
                                           {"conservative", CollisionMode::Conservative, 1}};
    return list;
}

struct Tally
{
    std::size_t falseNegatives = 0, falsePositives = 0;
};

struct SuiteResult
{
    std::string name;
    std::size_t states = 0, colliding = 0;
    std::vector<Tally> perSetting = std::vector<Tally>(settings().size());
    Tally fcl;
    double pixel = 0;
};

void evaluate(SuiteResult &result, const RobotModelConstPtr &robot, const SceneConstPtr &scene,
              const std::vector<double> &q)
{
    const Checker checker(robot, scene, CheckerOptions{BackendChoice::Cpu, 0});
    const CollisionModel &model = checker.collisionModel();
    const std::size_t n = q.size() / robot->numCoordinates(), dof = robot->numCoordinates();
    std::vector<std::uint8_t> truth(n);
    test::FclReference fcl(model);
    for (std::size_t i = 0; i < n; ++i)
    {
        truth[i] = test::bruteForceCollides(model, q.data() + i * dof, 0.0) ? 0 : 1;
        const bool fclValid = !fcl.collides(q.data() + i * dof);
        result.fcl.falseNegatives += fclValid && !truth[i];
        result.fcl.falsePositives += !fclValid && truth[i];
        result.colliding += !truth[i];
    }
    result.states += n;
    result.pixel = model.defaultPixelSize;
    for (std::size_t s = 0; s < settings().size(); ++s)
    {
        CollisionRequest request;
        request.mode = settings()[s].mode;
        request.pixelSize = model.defaultPixelSize * settings()[s].pixelScale;
        std::vector<std::uint8_t> valid(n);
        checker.check(q.data(), n, valid.data(), request);
        for (std::size_t i = 0; i < n; ++i)
        {
            result.perSetting[s].falseNegatives += valid[i] && !truth[i];
            result.perSetting[s].falsePositives += !valid[i] && truth[i];
        }
    }
}

void print(const std::vector<SuiteResult> &results)
{
    std::printf("| suite | states | colliding | default pixel |");
    for (const Setting &s : settings())
        std::printf(" %s FN/FP |", s.label.c_str());
    std::printf(" FCL FN/FP |\n|---|---:|---:|---:|");
    for (std::size_t s = 0; s <= settings().size(); ++s)
        std::printf("---:|");
    std::printf("\n");
    for (const SuiteResult &r : results)
    {
        std::printf("| %s | %zu | %zu | %.3g |", r.name.c_str(), r.states, r.colliding, r.pixel);
        for (const Tally &t : r.perSetting)
            std::printf(" %zu / %zu |", t.falseNegatives, t.falsePositives);
        std::printf(" %zu / %zu |\n", r.fcl.falseNegatives, r.fcl.falsePositives);
    }
}
}  // namespace

int main(int argc, char **argv)
{
    const int scenesPerScenario = argc > 1 ? std::atoi(argv[1]) : 2;
    const std::size_t statesPerScene = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 1000;
    const std::size_t statesPerBlindSpot = argc > 3 ? std::strtoul(argv[3], nullptr, 10) : 2000;
    const std::string root = bench::sharedDataOrExit();
    const RobotModelConstPtr panda = bench::loadMbmRobot(root, "panda");

    std::vector<SuiteResult> results;
    for (const std::string &scenario : bench::mbmScenarios())
    {
        SuiteResult result;
        result.name = "panda " + scenario;
        for (int index = 1; index <= scenesPerScenario; ++index)
            evaluate(result, panda, loadMoveItScene(bench::mbmProblemPath(root, "panda", scenario, index, "scene")),
                     bench::uniformStates(*panda, statesPerScene, 77u * index));
        results.push_back(result);
    }
    for (const test::BlindSpotSuite &suite : test::blindSpotSuites(statesPerBlindSpot))
    {
        SuiteResult result;
        result.name = suite.name;
        evaluate(result, suite.robot, suite.scene, suite.states);
        results.push_back(result);
    }
    std::printf(
        "FN = colliding state called valid, FP = free state called invalid, both against the exact oracle "
        "(every pair, triangle-triangle plus point-in-solid).\n\n");
    print(results);
    return 0;
}
