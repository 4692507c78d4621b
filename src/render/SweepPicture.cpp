#include "SweepPicture.h"

#include <algorithm>
#include <cmath>

#include "Canvas.h"
#include "rastercheck/core/Statistics.h"

namespace rastercheck::render
{
using detail::Anchor;
using detail::Colour;

void writeSweepPicture(const std::string &pngPath, const std::string &title, const std::vector<SweepPictureRow> &rows,
                       double timeLimit)
{
    const int rowHeight = 40, top = 70, left = 260, plotWidth = 560, gap = 30, barWidth = 160;
    const int width = left + plotWidth + gap + barWidth + 60;
    const int height = top + rowHeight * std::max<int>(1, static_cast<int>(rows.size())) + 50;
    detail::Canvas canvas(width, height);
    cairo_t *cr = canvas.context();

    // Times from a millisecond (or the fastest run) to the limit, in decades: sweeps mix runs of a
    // millisecond with runs at the limit, which a linear axis would crush into one pixel.
    double fastest = std::max(timeLimit, 1e-6);
    for (const SweepPictureRow &row : rows)
        for (double t : row.times)
            if (t > 0)
                fastest = std::min(fastest, t);
    const double lo = std::pow(10.0, std::floor(std::log10(std::min(fastest, 1e-3))));
    const double hi = std::pow(10.0, std::ceil(std::log10(std::max(timeLimit, lo * 10))));
    auto x = [&](double t)
    { return left + plotWidth * (std::log10(std::clamp(t, lo, hi)) - std::log10(lo)) / std::log10(hi / lo); };

    detail::setColour(cr, {0.1, 0.1, 0.1});
    detail::drawText(cr, title, 16, 28, 17, Anchor::Left, true);
    detail::drawText(cr, "planning time per run (s), log scale; blue: solved, grey: not solved; bar: median of solved",
                     16, 50, 11);
    detail::drawText(cr, "solved", left + plotWidth + gap, 50, 11, Anchor::Left, true);
    const double plotBottom = top + rowHeight * static_cast<double>(rows.size());
    cairo_set_line_width(cr, 1.0);
    for (double decade = lo; decade <= hi * 1.0001; decade *= 10)
    {
        detail::setColour(cr, {0.85, 0.85, 0.85});
        cairo_move_to(cr, x(decade), top);
        cairo_line_to(cr, x(decade), plotBottom);
        cairo_stroke(cr);
        detail::setColour(cr, {0.2, 0.2, 0.2});
        detail::drawText(cr, detail::formatTick(decade, decade), x(decade), plotBottom + 16, 11, Anchor::Centre);
    }
    detail::setColour(cr, {0.8, 0.2, 0.2});
    cairo_move_to(cr, x(timeLimit), top);
    cairo_line_to(cr, x(timeLimit), plotBottom);
    cairo_stroke(cr);
    detail::drawText(cr, "limit", x(timeLimit), top - 4, 10, Anchor::Centre);

    for (std::size_t r = 0; r < rows.size(); ++r)
    {
        const SweepPictureRow &row = rows[r];
        const double centre = top + rowHeight * (r + 0.5);
        detail::setColour(cr, {0.1, 0.1, 0.1});
        detail::drawText(cr, row.label, left - 10, centre + 4, 12, Anchor::Right);
        std::vector<double> solvedTimes;
        for (std::size_t i = 0; i < row.times.size(); ++i)
        {
            const bool solved = i < row.solved.size() && row.solved[i];
            if (solved)
                solvedTimes.push_back(row.times[i]);
            // A fixed spread across the row (golden-ratio steps): dots of equal times stay visible.
            const double spread = std::fmod(0.618034 * static_cast<double>(i), 1.0) - 0.5;
            detail::setColour(cr, solved ? Colour{0.15, 0.35, 0.8} : Colour{0.55, 0.55, 0.55}, 0.6);
            cairo_arc(cr, x(row.times[i]), centre + spread * rowHeight * 0.6, 2.5, 0, 2 * M_PI);
            cairo_fill(cr);
        }
        if (!solvedTimes.empty())
        {
            detail::setColour(cr, {0.05, 0.1, 0.3});
            cairo_set_line_width(cr, 3.0);
            const double m = x(median(solvedTimes));
            cairo_move_to(cr, m, centre - rowHeight * 0.4);
            cairo_line_to(cr, m, centre + rowHeight * 0.4);
            cairo_stroke(cr);
            cairo_set_line_width(cr, 1.0);
        }
        const double rate = row.times.empty() ? 0.0 : static_cast<double>(solvedTimes.size()) / row.times.size();
        const double barLeft = left + plotWidth + gap;
        detail::setColour(cr, {0.9, 0.9, 0.9});
        cairo_rectangle(cr, barLeft, centre - 8, barWidth, 16);
        cairo_fill(cr);
        detail::setColour(cr, {0.2, 0.6, 0.3});
        cairo_rectangle(cr, barLeft, centre - 8, barWidth * rate, 16);
        cairo_fill(cr);
        detail::setColour(cr, {0.1, 0.1, 0.1});
        detail::drawText(cr, std::to_string(solvedTimes.size()) + "/" + std::to_string(row.times.size()),
                         barLeft + barWidth + 6, centre + 4, 11);
    }
    canvas.writePng(pngPath);
}
}  // namespace rastercheck::render
