#include "rastercheck/io/SrdfLoader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <tinyxml2.h>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Log.h"

namespace rastercheck
{
namespace
{
std::string requireAttribute(const tinyxml2::XMLElement *element, const char *attribute, const std::string &file,
                             const std::string &where)
{
    const char *value = element->Attribute(attribute);
    if (!value || !*value)
        throw InputError(file, where, "missing attribute '" + std::string(attribute) + "'");
    return value;
}
}  // namespace

Srdf loadSrdfString(const std::string &xml, const std::string &sourceName)
{
    tinyxml2::XMLDocument document;
    if (document.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS)
        throw InputError(sourceName, "line " + std::to_string(document.ErrorLineNum()),
                         std::string("malformed XML: ") + document.ErrorStr());
    const tinyxml2::XMLElement *robot = document.FirstChildElement("robot");
    if (!robot)
        throw InputError(sourceName, "", "no <robot> root element");

    Srdf srdf;
    if (const char *name = robot->Attribute("name"))
        srdf.robotName = name;
    int k = 0;
    for (const tinyxml2::XMLElement *pair = robot->FirstChildElement("disable_collisions"); pair;
         pair = pair->NextSiblingElement("disable_collisions"), ++k)
    {
        const std::string where = "disable_collisions #" + std::to_string(k);
        srdf.disabledCollisions.emplace_back(requireAttribute(pair, "link1", sourceName, where),
                                             requireAttribute(pair, "link2", sourceName, where));
    }
    k = 0;
    for (const tinyxml2::XMLElement *state = robot->FirstChildElement("group_state"); state;
         state = state->NextSiblingElement("group_state"), ++k)
    {
        const std::string stateName = requireAttribute(state, "name", sourceName, "group_state #" + std::to_string(k));
        const std::string where = "group_state '" + stateName + "'";
        std::map<std::string, double> &values = srdf.groupStates[stateName];
        for (const tinyxml2::XMLElement *joint = state->FirstChildElement("joint"); joint;
             joint = joint->NextSiblingElement("joint"))
        {
            const std::string jointName = requireAttribute(joint, "name", sourceName, where + " joint");
            const std::string jointWhere = where + " joint '" + jointName + "'";
            const std::string text = requireAttribute(joint, "value", sourceName, jointWhere);
            std::istringstream tokens(text);
            std::vector<double> numbers;
            std::string token;
            while (tokens >> token)
            {
                char *end = nullptr;
                errno = 0;
                const double value = std::strtod(token.c_str(), &end);
                if (end == token.c_str() || *end != '\0' || !std::isfinite(value) || errno == ERANGE)
                    throw InputError(sourceName, jointWhere + " 'value'", "'" + token + "' is not a finite number");
                numbers.push_back(value);
            }
            if (numbers.size() == 1)
                values[jointName] = numbers[0];
            else
                // A multi-DOF joint's value list has no coordinate names in the SRDF; the model's layout
                // would be needed to place it, and no rastercheck robot uses one in a group state.
                logWarning(sourceName + ": " + jointWhere + ": " + std::to_string(numbers.size()) +
                           " values (multi-DOF joint) are ignored");
        }
    }
    return srdf;
}

Srdf loadSrdf(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw InputError(path, "", "file not found");
    std::ostringstream text;
    text << in.rdbuf();
    return loadSrdfString(text.str(), path);
}

void applySrdf(RobotModel &model, const Srdf &srdf)
{
    if (!srdf.robotName.empty() && srdf.robotName != model.name)
        logWarning("SRDF is for robot '" + srdf.robotName + "', applied to robot '" + model.name + "'");
    for (const auto &[first, second] : srdf.disabledCollisions)
    {
        const int a = model.linkIndex(first), b = model.linkIndex(second);
        if (a < 0 || b < 0)
        {
            logWarning("SRDF disable_collisions names link '" + (a < 0 ? first : second) + "', which robot '" +
                       model.name + "' lacks; pair skipped");
            continue;
        }
        const int ca = model.links[a].component, cb = model.links[b].component;
        if (ca >= 0 && cb >= 0)
            model.setCollisionAllowed(ca, cb, true);
    }
}
}  // namespace rastercheck
