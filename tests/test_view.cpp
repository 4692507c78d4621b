// The viewer's HTTP API (src/view): a server for the crane in the plant on a free port, every route
// called with known answers, every kind of bad request refused with a 4xx and a message, and many
// requests at once.
#include <atomic>
#include <cmath>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/model/Kinematics.h"
#include "view/ViewServer.h"
// After Eigen: httplib.h brings in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace rc = rastercheck;
using nlohmann::json;

namespace
{
using rastercheck::test::plant;

// Known states (tests/test_contacts.cpp, tests/browser): the crane facing the pipe rack, boom up
// and hook drawn up, is free; luffed down to 0.3 rad its boom goes through the rack.
const std::vector<double> kFree = {0, 0, 0, 1.570796326795, 0.834431313317, 5, 1};
const std::vector<double> kBoomInRack = {0, 0, 0, 1.570796326795, 0.3, 5, 1};
// The lift's start and goal (robots/sites/plant_lift.yaml): both free.
const std::vector<double> kStart = {0, 0, 0, -1.570796326795, 0.834431313317, 5, 15.800257730247};
const std::vector<double> kGoal = {0, 0, 0, 1.570796326795, 0.71942438464, 8.5, 20.933726302844};

constexpr std::size_t kMaxBody = 64 * 1024;
constexpr std::size_t kMaxStates = 1000;

std::string threeDirOrEmpty()
{
    try
    {
        return rc::view::findThreeDir();
    }
    catch (const rc::ConfigurationError &)
    {
        return "";
    }
}

/** \brief One server for the whole program, serving on a thread; stopped at exit. */
class ViewServerTest : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        rc::view::ViewContent content;
        content.title = "crane in plant.yaml";
        content.start = kStart;
        content.goal = kGoal;
        content.path = kStart;
        content.path.insert(content.path.end(), kGoal.begin(), kGoal.end());
        rc::view::ViewServerOptions options;
        options.port = 0;
        options.webDir = rastercheck::test::sourcePath("src/view/web");
        threeDir_ = threeDirOrEmpty();
        // Without three.js the page's own files are still served; /vendor/three then answers 404.
        options.threeDir = threeDir_.empty() ? options.webDir : threeDir_;
        options.maxBodyBytes = kMaxBody;
        options.maxBatchStates = kMaxStates;
        server_ = new rc::view::ViewServer(plant(), content, options);
        port_ = server_->bind();
        thread_ = new std::thread([] { server_->serve(); });
    }

    static void TearDownTestSuite()
    {
        server_->stop();
        thread_->join();
        delete thread_;
        delete server_;
    }

    static httplib::Client client()
    {
        httplib::Client client("127.0.0.1", port_);
        client.set_read_timeout(60, 0);  // a sanitized build is slow
        return client;
    }

    static json post(const std::string &body, int expectedStatus = 200)
    {
        httplib::Result result = client().Post("/api/check", body, "application/json");
        EXPECT_TRUE(result) << "no answer to " << body.substr(0, 200);
        if (!result)
            return json();
        EXPECT_EQ(result->status, expectedStatus) << body.substr(0, 200) << " -> " << result->body;
        EXPECT_EQ(result->get_header_value("Content-Type"), "application/json");
        return json::parse(result->body);
    }

    static json get(const std::string &path, int expectedStatus = 200)
    {
        httplib::Result result = client().Get(path.c_str());
        EXPECT_TRUE(result) << "no answer to GET " << path;
        if (!result)
            return json();
        EXPECT_EQ(result->status, expectedStatus) << path << " -> " << result->body.substr(0, 300);
        return json::parse(result->body);
    }

    /** \brief The answer to a bad request: \a expectedStatus and {"error": message containing \a what}. */
    static void expectRefused(const json &answer, const std::string &what)
    {
        ASSERT_TRUE(answer.is_object() && answer.contains("error")) << answer.dump();
        EXPECT_NE(answer["error"].get<std::string>().find(what), std::string::npos) << answer["error"];
    }

    static json checkBody(const std::vector<double> &q) { return json{{"q", q}}; }

    static rc::view::ViewServer *server_;
    static std::thread *thread_;
    static int port_;
    static std::string threeDir_;
};

rc::view::ViewServer *ViewServerTest::server_ = nullptr;
std::thread *ViewServerTest::thread_ = nullptr;
int ViewServerTest::port_ = 0;
std::string ViewServerTest::threeDir_;
}  // namespace

TEST_F(ViewServerTest, PortZeroPicksAFreePortAndTheUrlNamesIt)
{
    EXPECT_GT(port_, 0);
    EXPECT_EQ(server_->url(), "http://127.0.0.1:" + std::to_string(port_) + "/");
    // The port is taken now: a second server cannot bind it, and says so.
    rc::view::ViewServerOptions options;
    options.port = port_;
    options.webDir = rastercheck::test::sourcePath("src/view/web");
    options.threeDir = options.webDir;
    rc::view::ViewServer second(plant(), {}, options);
    EXPECT_THROW(second.bind(), rc::ConfigurationError);
}

TEST_F(ViewServerTest, ModelHasTheCoordinatesMeshesStartGoalAndPath)
{
    const json model = get("/api/model");
    const rc::RobotModel &robot = *plant().robot;
    EXPECT_EQ(model["title"], "crane in plant.yaml");
    EXPECT_EQ(model["robot"], "crawler_crane");
    EXPECT_EQ(model["mode"], "safe");
    ASSERT_EQ(model["coordinates"].size(), 7u);
    const std::vector<std::string> units = {"m", "m", "rad", "rad", "rad", "m", "m"};
    for (std::size_t i = 0; i < 7; ++i)
    {
        EXPECT_EQ(model["coordinates"][i]["name"], robot.coordinateNames[i]);
        EXPECT_EQ(model["coordinates"][i]["lower"].get<double>(), robot.lowerBounds[i]);
        EXPECT_EQ(model["coordinates"][i]["upper"].get<double>(), robot.upperBounds[i]);
        EXPECT_EQ(model["coordinates"][i]["unit"], units[i]) << robot.coordinateNames[i];
    }
    EXPECT_EQ(model["coordinates"][4]["upper"].get<double>(), 1.396263);  // luff
    EXPECT_EQ(model["start"].get<std::vector<double>>(), kStart);
    EXPECT_EQ(model["goal"].get<std::vector<double>>(), kGoal);
    EXPECT_EQ(model["path"], json({kStart, kGoal}));

    ASSERT_EQ(model["components"].size(), robot.numComponents());
    for (std::size_t c = 0; c < robot.numComponents(); ++c)
    {
        const json &component = model["components"][c];
        const rc::Mesh &mesh = robot.components[c].mesh;
        EXPECT_EQ(component["name"], robot.components[c].name);
        EXPECT_EQ(component["link"], robot.links[static_cast<std::size_t>(robot.components[c].link)].name);
        ASSERT_EQ(component["vertices"].size(), 3 * mesh.numVertices());
        ASSERT_EQ(component["triangles"].size(), 3 * mesh.numTriangles());
        // Link frame, as float.
        for (std::size_t v = 0; v < mesh.numVertices(); ++v)
            for (int k = 0; k < 3; ++k)
                EXPECT_EQ(component["vertices"][3 * v + k].get<float>(), static_cast<float>(mesh.vertices[v][k]));
        EXPECT_EQ(component["triangles"][0].get<std::uint32_t>(), mesh.triangles[0][0]);
    }
    const rc::Scene &scene = *plant().scene;
    ASSERT_EQ(model["objects"].size(), scene.numObjects());
    EXPECT_EQ(model["objects"][3]["name"], "pipe_rack_bent_00/0");
    std::size_t triangles = 0;
    for (const json &object : model["objects"])
        triangles += object["triangles"].size() / 3;
    EXPECT_EQ(triangles, scene.numTriangles());
}

TEST_F(ViewServerTest, FreeStateIsValidWithTheComponentPoses)
{
    const json answer = post(checkBody(kFree).dump());
    EXPECT_EQ(answer["valid"], true);
    EXPECT_TRUE(answer["contacts"].empty());
    EXPECT_GE(answer["milliseconds"].get<double>(), 0.0);
    // One pose per component: forward kinematics of the same state.
    const rc::RobotModel &robot = *plant().robot;
    rc::RobotData data(robot);
    rc::forwardKinematics(robot, data, kFree);
    ASSERT_EQ(answer["links"].size(), robot.numComponents());
    for (std::size_t c = 0; c < robot.numComponents(); ++c)
    {
        const Eigen::Isometry3d &pose = data.oMl[static_cast<std::size_t>(robot.components[c].link)];
        const json &entry = answer["links"][c];
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(entry["position"][k].get<double>(), pose.translation()[k], 1e-12);
        const std::vector<double> xyzw = entry["quaternion"].get<std::vector<double>>();
        const Eigen::Quaterniond rotation(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
        EXPECT_NEAR(rotation.norm(), 1.0, 1e-12);
        EXPECT_TRUE(rotation.toRotationMatrix().isApprox(pose.rotation(), 1e-12)) << robot.components[c].name;
    }
}

TEST_F(ViewServerTest, BoomInTheRackListsEveryContact)
{
    const json answer = post(checkBody(kBoomInRack).dump());
    EXPECT_EQ(answer["valid"], false);
    // The same contacts as Checker::contacts (tests/test_contacts.cpp holds those to an oracle).
    const rc::Checker checker(plant().robot, plant().scene);
    const std::vector<rc::Contact> contacts = checker.contacts(kBoomInRack.data());
    ASSERT_EQ(contacts.size(), 12u);
    ASSERT_EQ(answer["contacts"].size(), contacts.size());
    for (std::size_t i = 0; i < contacts.size(); ++i)
    {
        const json &entry = answer["contacts"][i];
        EXPECT_EQ(entry["kind"], "environment");
        EXPECT_EQ(entry["component"], plant().robot->components[static_cast<std::size_t>(contacts[i].component)].name);
        EXPECT_EQ(entry["object"], plant().scene->objects[static_cast<std::size_t>(contacts[i].object)].name);
        EXPECT_EQ(entry["triangle"], contacts[i].triangle);
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(entry["point"][k].get<double>(), contacts[i].position[k]);
        EXPECT_EQ(entry["description"], checker.describe(contacts[i]));
    }
    EXPECT_EQ(answer["contacts"][0]["component"], "boom_section_1");
    EXPECT_EQ(answer["contacts"][0]["object"], "pipe_rack_bent_06/0");
}

TEST_F(ViewServerTest, OutOfBoundsStateIsInvalidWithOneOutOfBoundsContact)
{
    std::vector<double> q = kFree;
    q[4] = 2.0;  // luff above its limit: a state the checker answers, not a bad request
    const json answer = post(checkBody(q).dump());
    EXPECT_EQ(answer["valid"], false);
    ASSERT_EQ(answer["contacts"].size(), 1u);
    EXPECT_EQ(answer["contacts"][0]["kind"], "out_of_bounds");
}

TEST_F(ViewServerTest, BatchGivesAVerdictAndTheFirstContactPerState)
{
    const json answer = post(json{{"states", {kFree, kBoomInRack, kStart, kGoal}}}.dump());
    EXPECT_EQ(answer["valid"], json({true, false, true, true}));
    ASSERT_EQ(answer["contacts"].size(), 4u);
    EXPECT_TRUE(answer["contacts"][0].is_null());
    EXPECT_TRUE(answer["contacts"][2].is_null());
    // The checker's first contact of the colliding state.
    const rc::Checker checker(plant().robot, plant().scene);
    rc::Contact first;
    ASSERT_FALSE(checker.isValid(kBoomInRack, {}, &first));
    EXPECT_EQ(answer["contacts"][1]["description"], checker.describe(first));
    EXPECT_EQ(answer["contacts"][1]["triangle"], first.triangle);
    // An empty batch is a batch.
    EXPECT_EQ(post(R"({"states": []})")["valid"], json::array());
}

TEST_F(ViewServerTest, RasterImageOfACollidingStateIsAPng)
{
    std::string query = "/api/raster?q=";
    for (std::size_t i = 0; i < kBoomInRack.size(); ++i)
        query += (i ? "," : "") + std::to_string(kBoomInRack[i]);
    httplib::Result result = client().Get(query.c_str());
    ASSERT_TRUE(result);
    ASSERT_EQ(result->status, 200) << result->body.substr(0, 300);
    EXPECT_EQ(result->get_header_value("Content-Type"), "image/png");
    const std::string &png = result->body;
    ASSERT_GT(png.size(), 1000u);
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    // IHDR: width and height, big-endian, after the 8-byte signature and the chunk header.
    const auto be32 = [&](std::size_t at)
    {
        return (std::uint32_t(std::uint8_t(png[at])) << 24) | (std::uint32_t(std::uint8_t(png[at + 1])) << 16) |
               (std::uint32_t(std::uint8_t(png[at + 2])) << 8) | std::uint32_t(std::uint8_t(png[at + 3]));
    };
    EXPECT_GE(be32(16), 720u);  // RasterPicture's smallest width
    EXPECT_GT(be32(20), 100u);
}

TEST_F(ViewServerTest, RasterImageOfAFreeStateIsNotFound)
{
    expectRefused(get("/api/raster?q=0,0,0,1.570796326795,0.834431313317,5,1", 404), "collision-free");
}

TEST_F(ViewServerTest, BadRasterQueriesAreRefused)
{
    expectRefused(get("/api/raster", 400), "expected ?q=");
    expectRefused(get("/api/raster?q=1,2,3", 400), "has 3 values");
    expectRefused(get("/api/raster?q=0,0,0,1,0.3,5,abc", 400), "'abc' is not a number");
    expectRefused(get("/api/raster?q=0,0,0,1,0.3,5,", 400), "is not a number");
    expectRefused(get("/api/raster?q=0,0,0,nan,0.3,5,1", 400), "not finite");
    expectRefused(get("/api/raster?q=0,0,0,inf,0.3,5,1", 400), "not finite");
}

TEST_F(ViewServerTest, BadCheckRequestsAreRefusedWithAMessage)
{
    expectRefused(post(R"({"q": [0, 0, 0,)", 400), "malformed JSON");
    expectRefused(post("", 400), "malformed JSON");
    expectRefused(post(R"({"q": [0, 0, 0, NaN, 0.3, 5, 1]})", 400), "malformed JSON");  // JSON has no NaN
    expectRefused(post("[1, 2, 3]", 400), R"(either "q")");
    expectRefused(post(R"({"q": [0,0,0,0,0,0,1], "states": []})", 400), R"(either "q")");
    expectRefused(post(R"({"p": 1})", 400), R"(either "q")");
    expectRefused(post(R"({"q": [0, 0, 0]})", 400), "q has 3 values; robot 'crawler_crane' has 7 coordinates");
    expectRefused(post(R"({"q": "0,0,0,0,0,0,1"})", 400), "must be an array");
    expectRefused(post(R"({"q": [0, 0, 0, "slew", 0.3, 5, 1]})", 400), "q[3] ('slew') is not a number");
    expectRefused(post(R"({"q": [0, 0, 0, null, 0.3, 5, 1]})", 400), "q[3] ('slew') is not a number");
    expectRefused(post(R"({"q": [0, 0, 0, 1e999, 0.3, 5, 1]})", 400), "number overflow");
    expectRefused(post(R"({"states": [[0, 0, 0, 0, 0.3, 5, 1], [0, 0]]})", 400), "states[1] has 2 values");
    expectRefused(post(R"({"states": {"a": 1}})", 400), "states must be an array");
}

TEST_F(ViewServerTest, OversizedRequestsAreRefused)
{
    // A body over the limit: httplib refuses it before reading it.
    const std::string huge = R"({"q": [)" + std::string(kMaxBody, ' ') + "0,0,0,0,0.3,5,1]}";
    httplib::Result result = client().Post("/api/check", huge, "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 413);
    expectRefused(json::parse(result->body), "over the limit");
    // More states than one batch may hold, in a body under the limit.
    json states = json::array();
    for (std::size_t i = 0; i <= kMaxStates; ++i)
        states.push_back({0, 0, 0, 0, 0.3, 5, 1});
    const std::string body = json{{"states", states}}.dump();
    ASSERT_LT(body.size(), kMaxBody);
    expectRefused(post(body, 413), "at most 1000 per request");
}

TEST_F(ViewServerTest, UnknownRoutesAndMethodsAreNotFound)
{
    expectRefused(get("/api/nothing", 404), "no route GET /api/nothing");
    expectRefused(get("/api/check", 404), "no route GET /api/check");
    httplib::Result result = client().Post("/api/model", "{}", "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 404);
    expectRefused(json::parse(result->body), "no route POST /api/model");
    expectRefused(get("/../../etc/passwd", 404), "no route");  // nothing outside the served folders
}

TEST_F(ViewServerTest, ServesThePageAndThreeJs)
{
    httplib::Result page = client().Get("/");
    ASSERT_TRUE(page);
    EXPECT_EQ(page->status, 200);
    EXPECT_NE(page->get_header_value("Content-Type").find("text/html"), std::string::npos);
    EXPECT_NE(page->body.find("viewer.js"), std::string::npos);
    httplib::Result script = client().Get("/viewer.js");
    ASSERT_TRUE(script);
    EXPECT_EQ(script->status, 200);
    EXPECT_EQ(script->get_header_value("Content-Type"), "text/javascript");  // a module needs it
    if (threeDir_.empty())
        GTEST_SKIP() << "three.js not installed (Debian's libjs-three): /vendor/three not checked";
    for (const char *path :
         {"/vendor/three/build/three.module.js", "/vendor/three/examples/jsm/controls/OrbitControls.js"})
    {
        httplib::Result three = client().Get(path);
        ASSERT_TRUE(three) << path;
        EXPECT_EQ(three->status, 200) << path;
        EXPECT_EQ(three->get_header_value("Content-Type"), "text/javascript") << path;
    }
}

TEST_F(ViewServerTest, ManyRequestsAtOnceGetTheirOwnAnswers)
{
    constexpr int kThreads = 8, kRequests = 20;
    std::atomic<int> right{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back(
            [&, t]
            {
                httplib::Client client("127.0.0.1", port_);
                client.set_read_timeout(60, 0);
                for (int r = 0; r < kRequests; ++r)
                {
                    const bool colliding = (t + r) % 2 == 1;
                    const std::string body = json{{"q", colliding ? kBoomInRack : kFree}}.dump();
                    httplib::Result result = client.Post("/api/check", body, "application/json");
                    if (!result || result->status != 200)
                        continue;
                    const json answer = json::parse(result->body);
                    if (answer["valid"] == !colliding && answer["contacts"].size() == (colliding ? 12u : 0u))
                        ++right;
                }
            });
    for (std::thread &thread : threads)
        thread.join();
    EXPECT_EQ(right.load(), kThreads * kRequests);
    // And the server is still there after every bad request above.
    EXPECT_EQ(get("/api/model")["robot"], "crawler_crane");
}

TEST(ViewFiles, PageAndThreeJsAreFoundOrTheErrorNamesWhereTheyWereLookedFor)
{
    // The build tree's page, found through the source tree whatever the executable's path.
    const std::string web = rc::view::findWebDir("/nonexistent/bin/rastercheck");
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(web) / "index.html"));
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(web) / "viewer.js"));
    // An environment variable, when set, is the only place looked at.
    const std::string copy = rastercheck::test::makeTempDir("view-web");
    rastercheck::test::writeFile(copy + "/index.html", "<!doctype html>");
    ::setenv("RASTERCHECK_WEB_DIR", copy.c_str(), 1);
    EXPECT_EQ(std::filesystem::path(rc::view::findWebDir("/nonexistent/bin/rastercheck")),
              std::filesystem::absolute(copy).lexically_normal());
    ::unsetenv("RASTERCHECK_WEB_DIR");
    ::setenv("RASTERCHECK_THREE_DIR", "/nonexistent/three", 1);
    try
    {
        rc::view::findThreeDir();
        ADD_FAILURE() << "a RASTERCHECK_THREE_DIR without three.js was accepted";
    }
    catch (const rc::ConfigurationError &e)
    {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/three/build/three.module.js"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("libjs-three"), std::string::npos) << e.what();
    }
    ::unsetenv("RASTERCHECK_THREE_DIR");
}

TEST(ViewCommand, TakesAStatesFileAndPrintsTheUrlOfTheFreePortItPicked)
{
    const std::string dir = rastercheck::test::makeTempDir("view-cli");
    const std::string path = rastercheck::test::writeFile(
        dir + "/path.csv",
        "base_x,base_y,base_yaw,slew,luff,telescope_1,hoist\n0,0,0,1.570796326795,0.834431313317,5,1\n"
        "0,0,0,1.570796326795,0.3,5,1\n");
    const std::string problem = "--robot " + rastercheck::test::sourcePath("robots/crane/crane.urdf") + " --srdf " +
                                rastercheck::test::sourcePath("robots/crane/crane.srdf") + " --scene " +
                                rastercheck::test::sourcePath("robots/sites/plant.yaml");
    // The server runs until stopped: stop it as soon as it has printed its URL (30 s at most).
    const std::string output = dir + "/output.txt";
    const rastercheck::test::CommandRun run = rastercheck::test::runCommand(
        std::string(RASTERCHECK_CLI) + " view " + problem + " --path " + path + " --port 0 > " + output +
        " 2>&1 & server=$!; for i in $(seq 300); do grep -q '^open http' " + output +
        " && break; sleep 0.1; done; kill $server && echo 'was serving'; cat " + output);
    EXPECT_NE(run.output.find("was serving"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("rastercheck view: crawler_crane, 7 coordinates, 101 scene objects"), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("open http://127.0.0.1:"), std::string::npos) << run.output;
    EXPECT_EQ(run.output.find("open http://127.0.0.1:0/"), std::string::npos) << run.output;
}

TEST(ViewCommand, BadArgumentsAreErrorsThatSayWhy)
{
    const std::string problem = "--robot " + rastercheck::test::sourcePath("robots/crane/crane.urdf") + " --scene " +
                                rastercheck::test::sourcePath("robots/sites/plant.yaml");
    rastercheck::test::CommandRun run = rastercheck::test::runCli("view " + problem + " --path /nonexistent/path.csv");
    EXPECT_EQ(run.status, 1) << run.output;
    EXPECT_NE(run.output.find("/nonexistent/path.csv"), std::string::npos) << run.output;
    run = rastercheck::test::runCli("view " + problem + " --port 70000");
    EXPECT_NE(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("--port"), std::string::npos) << run.output;
    run = rastercheck::test::runCli("view " + problem + " --path a.csv --request b.yaml");
    EXPECT_NE(run.status, 0) << run.output;
    EXPECT_NE(run.output.find("excludes"), std::string::npos) << run.output;
}
