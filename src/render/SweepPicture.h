#pragma once

#include <string>
#include <vector>

namespace rastercheck::render
{
/** \brief One row of a sweep picture: one robot and planner over every run of a sweep. */
struct SweepPictureRow
{
    std::string label;          ///< "panda / BatchRRTConnect"
    std::vector<double> times;  ///< every run's planning time (s); an unsolved run's is about the limit
    std::vector<bool> solved;   ///< per run: solved with a collision-free path
};

/** \brief Writes a PNG: per row, every run's time as a dot on a logarithmic axis (solved runs blue,
    unsolved grey) with the median of the solved ones marked, and the success rate as a bar. The time
    limit \a timeLimit (s) ends the axis. Throws InputError naming \a pngPath when it cannot be written. */
void writeSweepPicture(const std::string &pngPath, const std::string &title, const std::vector<SweepPictureRow> &rows,
                       double timeLimit);
}  // namespace rastercheck::render
