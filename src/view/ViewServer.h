#pragma once
// `rastercheck view`: a local HTTP server that shows a problem in the browser (three.js) and
// answers the page's collision questions with one Checker. The routes are documented in the README
// ("Live 3D viewer") and in docs/viewer.md.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rastercheck/collision/CollisionRequest.h"
#include "rastercheck/io/Problem.h"
#include "view/ConnectionLoop.h"

namespace rastercheck::view
{
/** \brief What the page shows besides the robot and the scene. Configurations have one value per
    coordinate of the robot, in its coordinate order. */
struct ViewContent
{
    /** \brief Shown as the page's title: what is being viewed ("crane in plant.yaml"). */
    std::string title;
    std::vector<double> start;  ///< empty when the problem has none
    std::vector<double> goal;   ///< empty when the problem has none
    /** \brief A path to play back, rows x dof (row-major); empty when none. */
    std::vector<double> path;
};

struct ViewServerOptions
{
    /** \brief Address to listen on. The default answers this machine only: the API lets anyone who
        reaches it make the server compute. */
    std::string host = "127.0.0.1";
    /** \brief Port; 0 picks a free one (bind() returns it). */
    int port = 8080;
    /** \brief Folder with the page (index.html, viewer.js): findWebDir(). */
    std::string webDir;
    /** \brief Root of three.js (build/three.module.js, examples/jsm/controls/OrbitControls.js),
        served under /vendor/three/: findThreeDir(). */
    std::string threeDir;
    /** \brief Largest request body accepted (bytes); a larger one gets 413. */
    std::size_t maxBodyBytes = std::size_t(8) << 20;
    /** \brief Most states one POST /api/check may hold; more get 413. */
    std::size_t maxBatchStates = 100000;
    /** \brief How every state is checked (mode, padding). */
    CollisionRequest request;
    /** \brief Connections: how many, how long idle or slow, and the worker threads that answer. */
    ConnectionLimits connections;
    /** \brief Batches (POST /api/check {"states"}) checked at once; more wait for one to finish. A
        single state or a raster picture runs on its request's worker thread. */
    int maxConcurrentBatches = 2;
    /** \brief Threads of one batch; 0 = the machine's cores divided by maxConcurrentBatches (at
        least 1), so that the batches at once do not oversubscribe the machine. */
    int checkerThreads = 0;
    /** \brief Longest time_limit POST /api/plan accepts (seconds). */
    double maxPlanSeconds = 60.0;
    /** \brief Where the detail of an internal error (a 500) goes; empty = standard error. */
    std::function<void(const std::string &)> log;
};

/** \brief What a ViewServer has done since start(): its connection loop's counts and the most
    batches that ran at once. */
struct ViewServerStats
{
    ConnectionStats connections;
    int peakConcurrentBatches = 0;
};

/** \brief The folder of the page's files: $RASTERCHECK_WEB_DIR when set (and then only it), else
    the installed copy (<prefix>/share/rastercheck/web beside <prefix>/bin/rastercheck, found from
    \a executable), else the source tree this build came from. Throws ConfigurationError naming the
    places tried when none holds index.html. */
std::string findWebDir(const std::string &executable);

/** \brief The root of three.js: $RASTERCHECK_THREE_DIR when set (and then only it), else the one CMake found at
    configure time (Debian's libjs-three: /usr/share/javascript/three). Throws ConfigurationError
    naming the places tried when none holds build/three.module.js. */
std::string findThreeDir();

/** \brief The viewer's HTTP server over one Checker. Routes (JSON unless said otherwise):
    - GET  /api/model: robot components and scene objects (meshes as flat vertex and triangle
      arrays; components in their link frame, objects in the world frame), coordinates with their
      limits and units, start, goal and path;
    - POST /api/check {"q": [...]}: verdict, every contact (Checker::contacts) and the pose of every
      component;
    - POST /api/check {"states": [[...], ...]}: one batch (Checker::check): a verdict and the first
      contact per state;
    - POST /api/plan {"start", "goal", "planner", "time_limit"} (each optional: the content's start
      and goal, BatchRRTConnect, 1 s): plans as `rastercheck plan` does (ompl::makeSimpleSetup,
      certified edges by default), one plan at a time (409 meanwhile); {"solved", "path": [[...],
      ...] (simplified), "seconds", "planner"}, and "message" when it found nothing (or the start or
      goal is invalid);
    - GET  /api/raster?q=v1,v2,...: the raster image (PNG, the paper's Fig. 6) of the state's first
      colliding pair;
    - GET  / and the page's files, and three.js under /vendor/three/.
    A malformed request (bad JSON, a configuration of the wrong length or not finite, a body over
    the limit, an unknown route) gets a 4xx answer {"error": message}; a handler never stops the
    server; an unexpected failure gets 500 with a generic message (the detail goes to the log).
    Only requests for the host and port bound are served (Host header: against DNS rebinding);
    /api/ refuses requests from another origin (Origin, Sec-Fetch-Site: a page elsewhere cannot
    drive it, not even through an <img>); POST bodies must be application/json. Requests are
    served concurrently (the Checker is thread-safe) by ConnectionLoop: idle or slow connections
    hold no thread. */
class ViewServer
{
public:
    /** \brief Builds the checker and the model's JSON. Throws ConfigurationError when the content's
        configurations do not have the robot's number of coordinates. */
    ViewServer(Problem problem, ViewContent content, ViewServerOptions options);
    ~ViewServer();
    ViewServer(const ViewServer &) = delete;
    ViewServer &operator=(const ViewServer &) = delete;

    /** \brief Binds the options' host and port and returns the port (the one the system picked
        when the options say 0). Throws ConfigurationError when it cannot bind. */
    int bind();
    /** \brief Starts serving on the server's own threads and returns; call after bind(). */
    void start();
    /** \brief start(), then waits until stop() (from another thread). Returns false when the
        server was not bound. */
    bool serve();
    /** \brief Stops serving: closes every connection, lets the requests being answered finish and
        joins the server's threads. Idempotent; the destructor calls it. Not from a handler. */
    void stop();
    ViewServerStats stats() const;
    /** \brief http://host:port/ once bound. */
    std::string url() const;
    /** \brief "cpu" or "cuda (<device>)": the checker's backend. */
    std::string backendName() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
}  // namespace rastercheck::view
