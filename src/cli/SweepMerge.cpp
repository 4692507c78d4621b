// rastercheck sweep merge: every log of a sweep into one SQLite database through OMPL's own
// ompl_benchmark_statistics (what Planner Arena reads), then a summary per robot and planner read back
// from that database, and a picture. Runs without a log are named and counted, never dropped.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <sqlite3.h>

#include "SweepSpec.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/core/Statistics.h"
#include "render/SweepPicture.h"

namespace rastercheck::cli
{
namespace
{
/** \brief The tool from OMPL's ompl-demos package: on PATH, else Debian's place. */
std::string statisticsTool()
{
    const char *path = std::getenv("PATH");
    std::istringstream folders(path ? path : "");
    std::string folder;
    while (std::getline(folders, folder, ':'))
        if (!folder.empty() && ::access((folder + "/ompl_benchmark_statistics").c_str(), X_OK) == 0)
            return folder + "/ompl_benchmark_statistics";
    if (::access("/usr/bin/ompl_benchmark_statistics", X_OK) == 0)
        return "/usr/bin/ompl_benchmark_statistics";
    throw ConfigurationError("ompl_benchmark_statistics not found (Debian package ompl-demos)");
}

/** \brief What became of one unit: its log, or why there is none. */
struct UnitOutcome
{
    const SweepTask *task = nullptr;
    const SweepUnit *unit = nullptr;
    bool logged = false;
    int status = -1;                ///< the plan's exit status; -1: the unit never finished
    double wall = std::nan("");     ///< seconds from fork to exit (process start, load, planning, log)
};

UnitOutcome outcomeOf(const std::string &dir, const SweepTask &task, const SweepUnit &unit)
{
    UnitOutcome outcome;
    outcome.task = &task;
    outcome.unit = &unit;
    const std::string log = dir + "/" + unitLogPath(task, unit);
    outcome.logged = pathExists(log);
    std::ifstream record(log + ".status");
    std::string key;
    double value = 0.0;
    while (record >> key >> value)
    {
        if (key == "status")
            outcome.status = static_cast<int>(value);
        else if (key == "wall_s")
            outcome.wall = value;
    }
    return outcome;
}

/** \brief One database row of the runs table, with what the summary needs. */
struct RunRow
{
    int experiment = 0;  ///< 1-based, in the order the logs were given
    std::string planner;
    bool solved = false;
    bool colliding = false;  ///< solved, but the exact re-check found a collision on the path
    double time = std::nan("");
    double states = std::nan("");
};

class Database
{
public:
    explicit Database(const std::string &path) : path_(path)
    {
        if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
            throw InputError(path, "", std::string("cannot open the database: ") + sqlite3_errmsg(db_));
    }
    ~Database() { sqlite3_close(db_); }
    Database(const Database &) = delete;
    Database &operator=(const Database &) = delete;

    /** \brief Rows of \a sql, every column as text (NULL as ""). */
    std::vector<std::vector<std::string>> query(const std::string &sql) const
    {
        sqlite3_stmt *statement = nullptr;
        if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK)
            throw InputError(path_, "", "query failed: " + std::string(sqlite3_errmsg(db_)) + " (" + sql + ")");
        std::vector<std::vector<std::string>> rows;
        while (sqlite3_step(statement) == SQLITE_ROW)
        {
            std::vector<std::string> row;
            for (int c = 0; c < sqlite3_column_count(statement); ++c)
            {
                const unsigned char *text = sqlite3_column_text(statement, c);
                row.emplace_back(text ? reinterpret_cast<const char *>(text) : "");
            }
            rows.push_back(std::move(row));
        }
        sqlite3_finalize(statement);
        return rows;
    }

    std::set<std::string> columns(const std::string &table) const
    {
        std::set<std::string> names;
        for (const auto &row : query("PRAGMA table_info(" + table + ")"))
            names.insert(row.at(1));
        return names;
    }

private:
    std::string path_;
    sqlite3 *db_ = nullptr;
};

double number(const std::string &text)
{
    if (text.empty())
        return std::nan("");
    try
    {
        return std::stod(text);
    }
    catch (const std::exception &)
    {
        return std::nan("");
    }
}

/** \brief "geometric_RRTConnect" -> "RRTConnect" (OMPL's benchmark prefixes the planner's kind). */
std::string plannerLabel(const std::string &name)
{
    const std::string prefix = "geometric_";
    return name.rfind(prefix, 0) == 0 ? name.substr(prefix.size()) : name;
}

std::string seconds(double value)
{
    if (std::isnan(value))
        return "-";
    std::ostringstream text;
    text << std::setprecision(3) << value;
    return text.str();
}
}  // namespace

int mergeSweep(const std::string &dir)
{
    const SweepPlan plan = loadSweepManifest(dir);
    std::vector<UnitOutcome> outcomes;
    std::vector<std::string> logs;
    std::vector<const UnitOutcome *> logged;  // experiment i + 1 of the database is logged[i]
    for (const SweepTask &task : plan.tasks)
        for (const SweepUnit &unit : task.units)
            outcomes.push_back(outcomeOf(dir, task, unit));
    for (const UnitOutcome &outcome : outcomes)
        if (outcome.logged)
        {
            logs.push_back(dir + "/" + unitLogPath(*outcome.task, *outcome.unit));
            logged.push_back(&outcome);
        }

    // A fresh database every time (experiment ids follow the order of the logs); written beside and
    // renamed, so a reader never sees half of one. The tool is given the logs in batches: a full
    // MotionBenchMaker sweep has more paths than one command line holds.
    const std::string database = dir + "/sweep.db";
    const std::string partial = database + ".partial";
    std::remove(partial.c_str());
    const std::string toolOutput = dir + "/out/statistics.out";
    std::remove(toolOutput.c_str());
    if (!logs.empty())
    {
        const std::string tool = statisticsTool();
        const std::size_t batch = 256;
        for (std::size_t first = 0; first < logs.size(); first += batch)
        {
            std::vector<std::string> arguments = {tool, "-d", partial};
            arguments.insert(arguments.end(), logs.begin() + static_cast<long>(first),
                             logs.begin() + static_cast<long>(std::min(logs.size(), first + batch)));
            const int status = waitForProcess(spawnProcess(arguments, toolOutput));
            if (status != 0)
                throw InputError(toolOutput, "", "ompl_benchmark_statistics failed (exit status " +
                                                     std::to_string(status) + ")");
        }
        if (std::rename(partial.c_str(), database.c_str()) != 0)
            throw InputError(database, "", "cannot write");
    }
    else
        std::remove(database.c_str());  // an older merge's database would claim runs that have no log now

    // Runs and experiments back from the database: the summary counts what Planner Arena will show.
    std::vector<RunRow> runs;
    std::vector<double> totalTimes;  // per experiment: OMPL's time to collect the data (s)
    if (!logs.empty())
    {
        Database db(database);
        for (const auto &row : db.query("SELECT id, totaltime FROM experiments ORDER BY id"))
            totalTimes.push_back(number(row.at(1)));
        if (totalTimes.size() != logs.size())
            throw InputError(database, "experiments",
                             std::to_string(totalTimes.size()) + " experiments from " + std::to_string(logs.size()) +
                                 " logs");
        const std::set<std::string> columns = db.columns("runs");
        auto column = [&](const std::string &name) { return columns.count(name) ? "r." + name : std::string("NULL"); };
        for (const auto &row :
             db.query("SELECT r.experimentid, p.name, r.solved, r.time, " + column("exact_recheck_collision_free") +
                      ", " + column("states_checked") +
                      " FROM runs r JOIN plannerConfigs p ON p.id = r.plannerid ORDER BY r.id"))
        {
            RunRow run;
            run.experiment = std::atoi(row.at(0).c_str());
            run.planner = plannerLabel(row.at(1));
            const bool solved = row.at(2) == "1";
            run.colliding = solved && row.at(4) == "0";
            run.solved = solved && !run.colliding;
            run.time = number(row.at(3));
            run.states = number(row.at(5));
            runs.push_back(std::move(run));
        }
    }

    // Per robot and planner, in the spec's planner order.
    struct Tally
    {
        std::vector<double> times, solvedTimes, states;
        std::vector<bool> solved;
        int colliding = 0;
    };
    std::map<std::string, std::map<std::string, Tally>> tallies;
    std::vector<std::string> robots;
    for (const RunRow &run : runs)
    {
        if (run.experiment < 1 || run.experiment > static_cast<int>(logged.size()))
            throw InputError(database, "runs", "a run of unknown experiment " + std::to_string(run.experiment));
        const std::string &robot = logged[static_cast<std::size_t>(run.experiment - 1)]->unit->robot;
        if (!tallies.count(robot))
            robots.push_back(robot);
        Tally &tally = tallies[robot][run.planner];
        tally.times.push_back(run.time);
        tally.solved.push_back(run.solved);
        if (run.solved)
            tally.solvedTimes.push_back(run.time);
        tally.colliding += run.colliding ? 1 : 0;
        if (!std::isnan(run.states))
            tally.states.push_back(run.states);
    }
    std::set<std::string> seenPlanners;
    std::vector<std::string> plannerOrder;
    for (const RunRow &run : runs)
        if (seenPlanners.insert(run.planner).second)
            plannerOrder.push_back(run.planner);

    std::size_t units = outcomes.size();
    std::vector<const UnitOutcome *> failed, missing;
    for (const UnitOutcome &outcome : outcomes)
        if (!outcome.logged)
            (outcome.status >= 0 ? failed : missing).push_back(&outcome);
    const std::size_t expectedRuns = units * plan.planners.size() * static_cast<std::size_t>(plan.runs);

    std::ostringstream md;
    md << "# Sweep " << plan.name << "\n\n"
       << "Spec `" << plan.specPath << "`: " << plan.tasks.size() << " task(s), " << units
       << " unit(s) (one `rastercheck plan` run per problem and seed), " << plan.planners.size() << " planner(s) x "
       << plan.runs << " run(s) of at most " << plan.timeLimit << " s.\n\n"
       << "**" << logs.size() << "/" << units << " unit(s) logged, " << failed.size() << " failed, " << missing.size()
       << " missing; " << runs.size() << "/" << expectedRuns << " run(s) in the database** (`sweep.db`, from "
       << "`ompl_benchmark_statistics`; Planner Arena reads it).\n\n";
    if (!failed.empty() || !missing.empty())
    {
        md << "## Missing and failed units\n\n"
           << "Running `rastercheck sweep run` again with the same spec and `--out` runs these again.\n\n";
        for (const UnitOutcome *outcome : failed)
            md << "- FAILED " << outcome->task->name << " " << outcome->unit->name << ": exit status "
               << outcome->status << " (see out/" << outcome->task->name << ".out)\n";
        for (const UnitOutcome *outcome : missing)
            md << "- MISSING " << outcome->task->name << " " << outcome->unit->name
               << ": no log (the task did not run, or was stopped before this unit finished)\n";
        md << "\n";
    }
    md << "## Results per robot and planner\n\n"
       << "Solved: a solution whose path the exact oracle re-checked collision-free; colliding: a solution whose "
          "path it did not (not counted as solved). Times are solve times of the solved runs (s); states checked: "
          "states the checker decided per run (median over all runs).\n\n"
       << "| robot | planner | runs | solved | colliding | median time (s) | p95 time (s) | states checked |\n"
       << "|---|---|---:|---:|---:|---:|---:|---:|\n";
    std::vector<render::SweepPictureRow> pictureRows;
    for (const std::string &robot : robots)
        for (const std::string &planner : plannerOrder)
        {
            const auto found = tallies[robot].find(planner);
            if (found == tallies[robot].end())
                continue;
            const Tally &tally = found->second;
            md << "| " << robot << " | " << planner << " | " << tally.times.size() << " | " << tally.solvedTimes.size()
               << " | " << tally.colliding << " | " << seconds(median(tally.solvedTimes)) << " | "
               << seconds(quantile(tally.solvedTimes, 0.95)) << " | "
               << (tally.states.empty() ? std::string("-") : std::to_string(std::llround(median(tally.states))))
               << " |\n";
            pictureRows.push_back({robot + " / " + planner, tally.times, tally.solved});
        }

    // Overhead: what a unit costs besides OMPL's benchmark loop (process start, problem load, checker
    // build, log writing), against the loop's time (planning, simplification, the exact re-check).
    double overhead = 0.0, planning = 0.0;
    std::vector<double> perUnit;
    for (std::size_t i = 0; i < logged.size(); ++i)
        if (!std::isnan(logged[i]->wall) && !std::isnan(totalTimes[i]))
        {
            perUnit.push_back(logged[i]->wall - totalTimes[i]);
            overhead += perUnit.back();
            planning += totalTimes[i];
        }
    if (!perUnit.empty())
        md << "\n## Overhead\n\n"
           << "Per unit, besides OMPL's benchmark loop (process start, problem load, checker build, log): median "
           << seconds(median(perUnit)) << " s; " << seconds(overhead) << " s in all against " << seconds(planning)
           << " s in the loops (" << seconds(planning > 0 ? 100.0 * overhead / planning : std::nan(""))
           << " %).\n";

    {
        std::ofstream out(dir + "/summary.md");
        out << md.str();
        if (!out.flush())
            throw InputError(dir + "/summary.md", "", "cannot write");
    }
    render::writeSweepPicture(dir + "/summary.png", "Sweep " + plan.name, pictureRows, plan.timeLimit);
    std::cout << md.str() << "\nsweep merge: wrote " << database << ", " << dir << "/summary.md and " << dir
              << "/summary.png" << std::endl;
    return failed.empty() && missing.empty() ? 0 : 2;
}
}  // namespace rastercheck::cli
