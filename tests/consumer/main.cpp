// Builds against the installed rastercheck package: forward kinematics on a two-link arm, and
// BatchRRTConnect from the planners library by its registered name.
#include <cmath>
#include <iostream>

#include <ompl/base/spaces/RealVectorStateSpace.h>

#include <rastercheck/model/Kinematics.h>
#include <rastercheck/ompl/Planners.h>

int main()
{
    rastercheck::RobotModel model;
    model.name = "consumer";
    model.links = {{"base", -1, -1}, {"arm", -1, -1}};
    rastercheck::Joint joint;
    joint.name = "shoulder";
    joint.kind = rastercheck::JointKind::Revolute;
    joint.parentLink = 0;
    joint.childLink = 1;
    joint.axis = Eigen::Vector3d::UnitZ();
    joint.origin.translation() = Eigen::Vector3d(1, 0, 0);
    joint.coordinateNames = {"shoulder"};
    joint.lower = {-M_PI};
    joint.upper = {M_PI};
    model.joints = {joint};
    model.finalize();
    rastercheck::RobotData data(model);
    rastercheck::forwardKinematics(model, data, std::vector<double>{M_PI / 2});
    const Eigen::Vector3d x = data.oMl[1].linear().col(0);
    const bool ok = std::abs(x.y() - 1.0) < 1e-12 && std::abs(data.oMl[1].translation().x() - 1.0) < 1e-12;
    auto space = std::make_shared<ompl::base::RealVectorStateSpace>(1);
    space->setBounds(-1, 1);
    const auto si = std::make_shared<ompl::base::SpaceInformation>(space);
    const bool planner = rastercheck::ompl::allocatePlanner("batchrrtconnect", si)->getName() == "BatchRRTConnect";
    std::cout << (!ok ? "consumer: wrong pose" : !planner ? "consumer: no BatchRRTConnect" : "consumer: ok") << '\n';
    return ok && planner ? 0 : 1;
}
