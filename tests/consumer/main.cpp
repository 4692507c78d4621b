// Builds against the installed rastercheck package and runs forward kinematics on a two-link arm.
#include <cmath>
#include <iostream>

#include <rastercheck/model/Kinematics.h>

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
    std::cout << (ok ? "consumer: ok" : "consumer: wrong pose") << '\n';
    return ok ? 0 : 1;
}
