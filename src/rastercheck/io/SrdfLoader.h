#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "rastercheck/model/RobotModel.h"

namespace rastercheck
{
/** \brief What rastercheck uses of an SRDF: pairs of links exempt from self-collision checks
    (`disable_collisions`) and named joint configurations (`group_state`). */
struct Srdf
{
    std::string robotName;
    std::vector<std::pair<std::string, std::string>> disabledCollisions;
    /** \brief group_state name -> (joint name -> value). */
    std::map<std::string, std::map<std::string, double>> groupStates;
};

/** \brief Parses an SRDF file. Throws InputError naming the file and element when malformed (XML
    syntax, a missing attribute, a value that is not a finite number). A group_state joint with
    several values (a multi-DOF joint) is skipped with a warning. */
Srdf loadSrdf(const std::string &path);
Srdf loadSrdfString(const std::string &xml, const std::string &sourceName = "<srdf>");

/** \brief Marks the SRDF's disabled pairs as allowed in \a model's allowed-collision matrix. A pair
    naming a link the model lacks is skipped with a warning (MoveIt does the same); pairs of links
    without collision geometry have no effect. */
void applySrdf(RobotModel &model, const Srdf &srdf);
}  // namespace rastercheck
