#include "rastercheck/io/StatesCsv.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "rastercheck/core/Error.h"
#include "rastercheck/core/Text.h"

namespace rastercheck
{
namespace
{
std::vector<std::string> splitCells(const std::string &line)
{
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ','))
        cells.push_back(trim(cell));
    if (!line.empty() && line.back() == ',')
        cells.emplace_back();
    return cells;
}
}  // namespace

StatesTable parseStatesCsv(const std::string &text, const std::vector<std::string> &coordinateNames,
                           const std::string &sourceName)
{
    std::istringstream input(text);
    std::string line;
    std::size_t lineNumber = 0;
    std::vector<std::string> header;
    while (header.empty() && std::getline(input, line))
    {
        ++lineNumber;
        if (!trim(line).empty())
            header = splitCells(line);
    }
    if (header.empty())
        throw InputError(sourceName, "header", "no header row (expected columns " +
                                                   (coordinateNames.empty() ? std::string("-") : coordinateNames[0]) +
                                                   ", ...)");

    std::vector<std::size_t> columnOf(coordinateNames.size());
    for (std::size_t i = 0; i < coordinateNames.size(); ++i)
    {
        std::size_t found = header.size();
        for (std::size_t c = 0; c < header.size(); ++c)
            if (header[c] == coordinateNames[i])
            {
                if (found != header.size())
                    throw InputError(sourceName, "column '" + coordinateNames[i] + "'", "appears twice in the header");
                found = c;
            }
        if (found == header.size())
            throw InputError(sourceName, "column '" + coordinateNames[i] + "'", "missing from the header");
        columnOf[i] = found;
    }

    StatesTable table;
    table.dof = coordinateNames.size();
    while (std::getline(input, line))
    {
        ++lineNumber;
        if (trim(line).empty())
            continue;
        const std::vector<std::string> cells = splitCells(line);
        for (std::size_t i = 0; i < coordinateNames.size(); ++i)
        {
            const std::string where = "line " + std::to_string(lineNumber) + " column '" + coordinateNames[i] + "'";
            if (columnOf[i] >= cells.size())
                throw InputError(sourceName, where, "row has only " + std::to_string(cells.size()) + " cells");
            const std::string &cell = cells[columnOf[i]];
            char *end = nullptr;
            errno = 0;
            const double value = std::strtod(cell.c_str(), &end);
            if (cell.empty() || end != cell.c_str() + cell.size())
                throw InputError(sourceName, where, "'" + cell + "' is not a number");
            table.values.push_back(value);
        }
        ++table.rows;
    }
    return table;
}

StatesTable readStatesCsv(const std::string &path, const std::vector<std::string> &coordinateNames)
{
    std::ifstream file(path, std::ios::binary);
    if (!file)
        throw InputError(path, "", "cannot open the states file");
    std::ostringstream text;
    text << file.rdbuf();
    return parseStatesCsv(text.str(), coordinateNames, path);
}
void writeStatesCsv(const std::string &path, const std::vector<std::string> &coordinateNames,
                    const std::vector<double> &values)
{
    const std::size_t dof = coordinateNames.size();
    std::ofstream out(path);
    if (!out)
        throw InputError(path, "", "cannot write the states file");
    for (std::size_t i = 0; i < dof; ++i)
        out << (i ? "," : "") << coordinateNames[i];
    out << '\n' << std::setprecision(17);
    for (std::size_t r = 0; dof > 0 && r + dof <= values.size(); r += dof)
        for (std::size_t i = 0; i < dof; ++i)
            out << values[r + i] << (i + 1 < dof ? ',' : '\n');
    if (!out.flush())
        throw InputError(path, "", "cannot write the states file");
}
}  // namespace rastercheck
