// The start and goal states of the MotionBenchMaker problems, decided by rastercheck and by FCL with
// the scenes' and robot's primitives as FCL shapes (fcl::Sphered, Boxd, Cylinderd: as MoveIt
// loads them; meshes as BVHModel<OBBRSS>; the SRDF's pairs exempt): how many verdicts agree, and
// every state where they do not. States within the bounds tolerance (1e-4; a goal's joint
// constraint tolerance where larger) outside a joint limit are moved onto it first, as `plan`
// does; "raw" compares rastercheck without that move (a state outside a limit is invalid) with
// FCL's verdict on the moved state (FCL sees geometry only): the "before".
//
// usage: rastercheck_bench_endpoints [robots=fetch] [problems_per_scenario=100]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "BenchSupport.h"
#include "Reference.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Log.h"
#include "rastercheck/model/Bounds.h"
#include "rastercheck/ompl/Setup.h"

namespace rc = rastercheck;

int main(int argc, char **argv)
{
    const std::string root = rc::bench::sharedDataOrExit();
    const std::vector<std::string> robots = rc::bench::splitList(argc > 1 ? argv[1] : "fetch");
    const int problems = argc > 2 ? std::atoi(argv[2]) : 100;
    rc::setLogHandler([](rc::LogLevel, const std::string &) {});  // the robot's loader notes, per scene
    std::printf(
        "| robot | states | moved onto a bound | rastercheck invalid (safe) | of them self | FCL invalid | "
        "verdicts equal | equal, raw |\n|---|---|---|---|---|---|---|---|\n");
    for (const std::string &name : robots)
    {
        const rc::RobotModelConstPtr robot = rc::bench::loadMbmRobot(root, name);
        const rc::ompl::StateMapping mapping(robot);
        int states = 0, moved = 0, ours = 0, self = 0, theirs = 0, equal = 0, equalRaw = 0;
        std::vector<std::string> differences;
        for (const std::string &scenario : rc::bench::mbmScenarios())
            for (int index = 1; index <= problems; ++index)
            {
                const std::string scenePath = rc::bench::mbmProblemPath(root, name, scenario, index, "scene");
                const rc::ScenePtr scene = rc::loadMoveItScene(scenePath);
                const rc::MotionPlanRequest request =
                    rc::loadMoveItRequest(rc::bench::mbmProblemPath(root, name, scenario, index, "request"));
                const rc::Checker checker(robot, scene, rc::CheckerOptions{rc::BackendChoice::Cpu});
                rc::test::FclReference fcl(checker.collisionModel(), true);
                std::vector<double> slackDown(robot->numCoordinates(), 0.0), slackUp(robot->numCoordinates(), 0.0);
                for (const auto &[joint, tolerance] : request.goalToleranceBelow)
                    if (robot->coordinateIndex(joint) >= 0)
                        slackDown[static_cast<std::size_t>(robot->coordinateIndex(joint))] = tolerance;
                for (const auto &[joint, tolerance] : request.goalToleranceAbove)
                    if (robot->coordinateIndex(joint) >= 0)
                        slackUp[static_cast<std::size_t>(robot->coordinateIndex(joint))] = tolerance;
                for (const char *what : {"start", "goal"})
                {
                    const bool goal = std::string(what) == "goal";
                    std::vector<double> q = rc::ompl::configurationFromJoints(
                        mapping, goal ? request.goalJoints : request.startJoints, what, rc::ompl::UnknownJoints::Skip);
                    const bool rawValid = checker.isValid(q);
                    const rc::BoundsFit fit =
                        goal ? rc::fitToBounds(*robot, q.data(), rc::kDefaultBoundsTolerance, slackDown, slackUp)
                             : rc::fitToBounds(*robot, q.data(), rc::kDefaultBoundsTolerance);
                    rc::Contact contact;
                    const bool valid = checker.isValid(q, {}, &contact);
                    const bool fclValid = !fcl.collides(q.data());
                    ++states;
                    moved += !fit.moved.empty();
                    ours += !valid;
                    self += !valid && contact.kind == rc::Contact::Kind::SelfCollision;
                    theirs += !fclValid;
                    equal += valid == fclValid;
                    equalRaw += rawValid == fclValid;
                    if (valid != fclValid)
                        differences.push_back(scenario + " " + std::to_string(index) + " " + what + ": rastercheck " +
                                              (valid ? "valid" : checker.describe(contact)) + ", FCL " +
                                              (fclValid ? "valid" : "invalid"));
                }
            }
        std::printf("| %s | %d | %d | %d | %d | %d | %d | %d |\n", name.c_str(), states, moved, ours, self, theirs,
                    equal, equalRaw);
        for (const std::string &line : differences)
            std::printf("  differs: %s\n", line.c_str());
    }
    return 0;
}
