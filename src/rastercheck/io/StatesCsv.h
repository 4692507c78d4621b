#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rastercheck
{
/** \brief A batch of configurations read from CSV, in a model's coordinate order. */
struct StatesTable
{
    std::size_t rows = 0;
    std::size_t dof = 0;
    std::vector<double> values;  ///< rows x dof, row-major
};

/** \brief Reads a CSV with a header row. Columns are matched by name to \a coordinateNames (any
    order; other columns are ignored). Cells are decimal numbers; "nan" and "inf" are read as such
    (the checker then calls that state invalid). Blank lines are skipped. Throws InputError naming
    the file and the column (missing, duplicated) or line and column (a cell that is not a number,
    a short row). */
StatesTable readStatesCsv(const std::string &path, const std::vector<std::string> &coordinateNames);
StatesTable parseStatesCsv(const std::string &text, const std::vector<std::string> &coordinateNames,
                           const std::string &sourceName = "<csv>");

/** \brief Writes \a values (rows x coordinateNames.size(), row-major) as the CSV readStatesCsv reads:
    a header row of \a coordinateNames, one state per row, every value with 17 significant digits
    (read back, the same doubles). Throws InputError when \a path cannot be written. */
void writeStatesCsv(const std::string &path, const std::vector<std::string> &coordinateNames,
                    const std::vector<double> &values);
}  // namespace rastercheck
