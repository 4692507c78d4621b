// The viewer's HTTP API (src/view): a server for the crane in the plant on a free port, every route
// called with known answers, every kind of bad request refused with a 4xx and a message, and many
// requests at once.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "TestSupport.h"
#include "rastercheck/collision/Checker.h"
#include "rastercheck/core/Error.h"
#include "rastercheck/io/MoveItYaml.h"
#include "rastercheck/model/Kinematics.h"
#include "rastercheck/ompl/Setup.h"
#include "rastercheck/ompl/StateMapping.h"
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
constexpr int kMaxBatches = 2;

/** \brief scripts/sanitize.sh shrinks the load tests with it. */
constexpr const char *kLoadScale = "RASTERCHECK_VIEW_LOAD_SCALE";

bool fullSize()
{
    return rastercheck::test::scaleFromEnvironment(kLoadScale) >= 1.0;
}

/** \brief A TCP connection to the server that sends only what it is told to (an idle or slow
    client, or a hand-written request). */
class RawConnection
{
public:
    explicit RawConnection(int port) : fd_(::socket(AF_INET, SOCK_STREAM, 0))
    {
        sockaddr_in address{};
        address.sin_family = AF_INET;
        address.sin_port = htons(static_cast<std::uint16_t>(port));
        address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        connected_ = ::connect(fd_, reinterpret_cast<const sockaddr *>(&address), sizeof address) == 0;
    }
    ~RawConnection() { ::close(fd_); }
    RawConnection(const RawConnection &) = delete;
    RawConnection &operator=(const RawConnection &) = delete;

    bool connected() const { return connected_; }
    void send(const std::string &text) { EXPECT_EQ(::send(fd_, text.data(), text.size(), MSG_NOSIGNAL), ssize_t(text.size())); }
    /** \brief Everything the server sends until it closes the connection (or \a seconds pass). */
    std::string receiveUntilClosed(int seconds)
    {
        timeval timeout{seconds, 0};
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
        std::string text;
        char chunk[4096];
        for (;;)
        {
            const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
            if (n <= 0)
            {
                closedByServer_ = n == 0;
                return text;
            }
            text.append(chunk, static_cast<std::size_t>(n));
        }
    }
    bool closedByServer() const { return closedByServer_; }

private:
    int fd_;
    bool connected_ = false;
    bool closedByServer_ = false;
};

double percentile(std::vector<double> values, double fraction)
{
    std::sort(values.begin(), values.end());
    return values[std::min(values.size() - 1, static_cast<std::size_t>(fraction * values.size()))];
}

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
        options.maxConcurrentBatches = kMaxBatches;
        server_ = new rc::view::ViewServer(plant(), content, options);
        port_ = server_->bind();
        server_->start();
    }

    static void TearDownTestSuite()
    {
        server_->stop();
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
        return postTo("/api/check", body, expectedStatus);
    }

    static json postTo(const std::string &route, const std::string &body, int expectedStatus = 200)
    {
        httplib::Result result = client().Post(route.c_str(), body, "application/json");
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

    /** \brief \a clients threads at once, each with its own connection, each sending \a perClient
        requests: request(client, t, r) sends request r of thread t and says whether the answer was
        right. Returns how many were. */
    static int fromClients(int clients, int perClient,
                           const std::function<bool(httplib::Client &client, int t, int r)> &request)
    {
        std::atomic<int> right{0};
        std::vector<std::thread> threads;
        for (int t = 0; t < clients; ++t)
            threads.emplace_back(
                [&, t]
                {
                    httplib::Client client("127.0.0.1", port_);
                    client.set_read_timeout(60, 0);  // a sanitized build is slow
                    for (int r = 0; r < perClient; ++r)
                        right += request(client, t, r);
                });
        for (std::thread &thread : threads)
            thread.join();
        return right.load();
    }

    /** \brief Waits (2 s at most) until the server has closed every connection its clients closed. */
    static std::size_t openConnectionsAfterClientsLeft()
    {
        for (int i = 0; i < 100 && server_->stats().connections.open > 0; ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return server_->stats().connections.open;
    }

    static rc::view::ViewServer *server_;
    static int port_;
    static std::string threeDir_;
};

rc::view::ViewServer *ViewServerTest::server_ = nullptr;
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

TEST_F(ViewServerTest, FreeStateHasItsClearanceAndAColliderNone)
{
    const json free = post(checkBody(kFree).dump());
    ASSERT_TRUE(free["distance"].is_object()) << free.dump();
    // The checker's exact distance: the same value, pair and points.
    const rc::Checker checker(plant().robot, plant().scene);
    rc::DistanceResult expected;
    checker.distance(kFree.data(), rc::DistanceRequest{}, &expected);
    ASSERT_GT(expected.distance, 0.0);
    EXPECT_EQ(free["distance"]["distance"].get<double>(), expected.distance);
    EXPECT_EQ(free["distance"]["component"], plant().robot->components[expected.component].name);
    const std::vector<double> a = free["distance"]["points"][0].get<std::vector<double>>();
    const std::vector<double> b = free["distance"]["points"][1].get<std::vector<double>>();
    EXPECT_NEAR(std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]), expected.distance, 1e-9);
    EXPECT_TRUE(post(checkBody(kBoomInRack).dump())["distance"].is_null());
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
    // Nested 30 000 deep, cut off and whole (parsed and destroyed without recursion).
    expectRefused(post(R"({"q": )" + std::string(30000, '['), 400), "malformed JSON");
    expectRefused(post(std::string(30000, '[') + std::string(30000, ']'), 400), R"(either "q")");
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
    const int right = fromClients(kThreads, kRequests,
                                  [](httplib::Client &client, int t, int r)
                                  {
                                      const bool colliding = (t + r) % 2 == 1;
                                      const std::string body = json{{"q", colliding ? kBoomInRack : kFree}}.dump();
                                      httplib::Result result = client.Post("/api/check", body, "application/json");
                                      if (!result || result->status != 200)
                                          return false;
                                      const json answer = json::parse(result->body);
                                      return answer["valid"] == !colliding &&
                                             answer["contacts"].size() == (colliding ? 12u : 0u);
                                  });
    EXPECT_EQ(right, kThreads * kRequests);
    // And the server is still there after every bad request above.
    EXPECT_EQ(get("/api/model")["robot"], "crawler_crane");
}

TEST_F(ViewServerTest, RequestsForAnotherHostAreRefused)
{
    // DNS rebinding: a page at evil.example whose name now points to 127.0.0.1 sends its own Host.
    const std::string port = std::to_string(port_);
    for (const std::string &host :
         std::vector<std::string>{"evil.example:" + port, "127.0.0.1:1", "127.0.0.1", "localhost.evil.example:" + port})
    {
        httplib::Result result = client().Get("/api/model", {{"Host", host}});
        ASSERT_TRUE(result) << host;
        EXPECT_EQ(result->status, 403) << host;
        expectRefused(json::parse(result->body), "is not this server");
        result = client().Get("/", {{"Host", host}});
        ASSERT_TRUE(result) << host;
        EXPECT_EQ(result->status, 403) << host << ": the page too";
    }
    // The loopback names of the same port are this server.
    for (const std::string &host :
         std::vector<std::string>{"127.0.0.1:" + port, "localhost:" + port, "LOCALHOST:" + port, "[::1]:" + port})
    {
        httplib::Result result = client().Get("/api/model", {{"Host", host}});
        ASSERT_TRUE(result) << host;
        EXPECT_EQ(result->status, 200) << host << " -> " << result->body.substr(0, 200);
    }
}

TEST_F(ViewServerTest, CrossOriginApiRequestsAreRefused)
{
    const std::string body = checkBody(kFree).dump();
    const std::string self = "http://127.0.0.1:" + std::to_string(port_);
    httplib::Result result = client().Post("/api/check", {{"Origin", "http://evil.example"}}, body, "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 403);
    expectRefused(json::parse(result->body), "cross-origin request from 'http://evil.example'");
    result = client().Post("/api/check", {{"Origin", "null"}}, body, "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 403);
    // An <img src=.../api/raster?q=...> on another site sends no Origin, but its Sec-Fetch-Site.
    std::string raster = "/api/raster?q=";
    for (std::size_t i = 0; i < kBoomInRack.size(); ++i)
        raster += (i ? "," : "") + std::to_string(kBoomInRack[i]);
    result = client().Get(raster.c_str(), {{"Sec-Fetch-Site", "cross-site"}});
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 403);
    expectRefused(json::parse(result->body), "Sec-Fetch-Site: cross-site");
    // The page itself (same origin) is served, and so is a link to the page from elsewhere.
    result = client().Post("/api/check", {{"Origin", self}, {"Sec-Fetch-Site", "same-origin"}}, body,
                           "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << result->body;
    result = client().Get("/", {{"Sec-Fetch-Site", "cross-site"}});
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200);
}

TEST_F(ViewServerTest, PostBodiesMustBeJson)
{
    // A cross-site form or fetch can send text/plain without a preflight; application/json it cannot.
    const std::string body = checkBody(kFree).dump();
    for (const char *type : {"text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x",
                             "application/jsonp", ""})
    {
        httplib::Result result = client().Post("/api/check", body, type);
        ASSERT_TRUE(result) << type;
        EXPECT_EQ(result->status, 415) << type;
        expectRefused(json::parse(result->body), "must be application/json");
    }
    httplib::Result result = client().Post("/api/check", body, "Application/JSON; charset=utf-8");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200) << result->body;
}

TEST_F(ViewServerTest, ManyLargeBatchesAtOnceRunAtMostTheBoundAtATime)
{
    const int clients = 8, batches = 3;
    const std::size_t states = kMaxStates;
    json batch = json::array();
    for (std::size_t i = 0; i < states; ++i)
        batch.push_back(i % 3 == 0 ? kBoomInRack : kFree);
    const std::string body = json{{"states", batch}}.dump();
    const int right = fromClients(clients, batches,
                                  [&](httplib::Client &client, int, int)
                                  {
                                      httplib::Result result = client.Post("/api/check", body, "application/json");
                                      if (!result || result->status != 200)
                                          return false;
                                      const json answer = json::parse(result->body);
                                      bool all = answer["valid"].size() == states;
                                      for (std::size_t i = 0; all && i < states; ++i)
                                          all = answer["valid"][i] == (i % 3 != 0);
                                      return all;
                                  });
    EXPECT_EQ(right, clients * batches);
    const rc::view::ViewServerStats stats = server_->stats();
    EXPECT_GE(stats.peakConcurrentBatches, 1);
    EXPECT_LE(stats.peakConcurrentBatches, kMaxBatches);
}

TEST_F(ViewServerTest, IdleAndSlowConnectionsDoNotDelayAnswers)
{
    // 64 connections that send nothing and 8 that stop in the middle of their request: each held one
    // of httplib's pool threads until its timeout (a check waited 3.8 s behind 8 idle ones).
    std::vector<std::unique_ptr<RawConnection>> idle;
    for (int i = 0; i < 64; ++i)
        idle.push_back(std::make_unique<RawConnection>(port_));
    for (int i = 0; i < 8; ++i)
    {
        idle.push_back(std::make_unique<RawConnection>(port_));
        idle.back()->send("POST /api/check HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port_) +
                          "\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{\"q\": [0,");
    }
    for (const auto &connection : idle)
        ASSERT_TRUE(connection->connected());
    std::vector<double> milliseconds;
    for (int i = 0; i < 5; ++i)
    {
        const auto start = std::chrono::steady_clock::now();
        EXPECT_EQ(post(checkBody(i % 2 ? kBoomInRack : kFree).dump())["valid"], i % 2 == 0);
        milliseconds.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    const double median = percentile(milliseconds, 0.5);
    std::cout << "a check with 72 idle or stalled connections open: median " << median << " ms of 5\n";
    if (fullSize())  // a sanitized build is 10-50x slower
    {
        EXPECT_LT(median, 100.0);
    }
}

TEST_F(ViewServerTest, InternalErrorsAnswerAGenericMessageAndLogTheDetail)
{
    // A request the checker cannot take (a per-pair padding of the wrong size: a programming error of
    // whoever embeds the server) throws inside the handler: the client learns nothing of it.
    rc::view::ViewServerOptions options;
    options.port = 0;
    options.webDir = rastercheck::test::sourcePath("src/view/web");
    options.threeDir = options.webDir;
    auto padding = std::make_shared<rc::PairPadding>();
    padding->environment = {0.1};
    options.request.pairPadding = padding;
    std::mutex logMutex;
    std::string log;
    options.log = [&](const std::string &line)
    {
        std::lock_guard<std::mutex> lock(logMutex);
        log += line + "\n";
    };
    rc::view::ViewServer server(plant(), {}, options);
    const int port = server.bind();
    server.start();
    httplib::Client client("127.0.0.1", port);
    client.set_read_timeout(60, 0);
    httplib::Result result = client.Post("/api/check", checkBody(kFree).dump(), "application/json");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 500);
    const json answer = json::parse(result->body);
    EXPECT_EQ(answer["error"], "internal error (the server's log has the detail)");
    server.stop();
    EXPECT_NE(log.find("internal error answering POST /api/check"), std::string::npos) << log;
    EXPECT_NE(log.find("pairPadding"), std::string::npos) << log;
}

TEST_F(ViewServerTest, StopJoinsTheServingThreadsAndClosesEveryConnection)
{
    const std::size_t threadsBefore = rastercheck::test::ProcessFootprint::now().threads;
    std::size_t threadsServing = 0;
    {
        rc::view::ViewServerOptions options;
        options.port = 0;
        options.webDir = rastercheck::test::sourcePath("src/view/web");
        options.threeDir = options.webDir;
        options.connections.workers = 3;
        rc::view::ViewServer server(plant(), {}, options);
        const int port = server.bind();
        std::thread serving([&] { EXPECT_TRUE(server.serve()); });
        RawConnection waiting(port);
        ASSERT_TRUE(waiting.connected());
        // serve() has started the loop once a request is answered.
        httplib::Client client("127.0.0.1", port);
        client.set_read_timeout(60, 0);
        httplib::Result result = client.Get("/api/model");
        ASSERT_TRUE(result);
        EXPECT_EQ(result->status, 200);
        threadsServing = rastercheck::test::ProcessFootprint::now().threads;
        server.stop();  // returns once every thread of the server is joined
        serving.join();
        EXPECT_EQ(waiting.receiveUntilClosed(5), "");
        EXPECT_TRUE(waiting.closedByServer());
    }
    EXPECT_GE(threadsServing, threadsBefore + 4 + 1);  // 3 workers and the loop (and serve()'s caller)
    EXPECT_EQ(rastercheck::test::ProcessFootprint::now().threads, threadsBefore);
}

TEST(ViewServerLimits, IdleAndIncompleteConnectionsTimeOutAndTheIdlestMakesRoom)
{
    rc::view::ViewServerOptions options;
    options.port = 0;
    options.webDir = rastercheck::test::sourcePath("src/view/web");
    options.threeDir = options.webDir;
    options.connections.idleTimeout = std::chrono::milliseconds(300);
    options.connections.requestTimeout = std::chrono::milliseconds(600);
    options.connections.maxConnections = 4;
    rc::view::ViewServer server(plant(), {}, options);
    const int port = server.bind();
    server.start();
    const std::string host = "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";

    // An idle connection is closed after the idle timeout, a request that stops half way is answered
    // 408 after the request timeout.
    {
        RawConnection idle(port), slow(port);
        slow.send("GET /api/model HTTP/1.1\r\n" + host);
        const auto start = std::chrono::steady_clock::now();
        EXPECT_EQ(idle.receiveUntilClosed(10), "");
        EXPECT_TRUE(idle.closedByServer());
        const std::string answer = slow.receiveUntilClosed(10);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        EXPECT_EQ(answer.rfind("HTTP/1.1 408", 0), 0u) << answer;
        EXPECT_NE(answer.find("did not arrive whole within 600 ms"), std::string::npos) << answer;
        EXPECT_GE(seconds, 0.5);
        EXPECT_LT(seconds, 5.0);
    }
    // Four connections open (the limit), all idle: a fifth one closes the idlest and is answered.
    std::vector<std::unique_ptr<RawConnection>> idle;
    for (int i = 0; i < 4; ++i)
        idle.push_back(std::make_unique<RawConnection>(port));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    httplib::Client client("127.0.0.1", port);
    client.set_read_timeout(60, 0);
    httplib::Result result = client.Get("/api/model");
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 200);
    EXPECT_EQ(idle[0]->receiveUntilClosed(5), "");
    EXPECT_TRUE(idle[0]->closedByServer()) << "the connection idle the longest makes room";
    const rc::view::ViewServerStats stats = server.stats();
    EXPECT_GE(stats.connections.evicted, 1u);
    EXPECT_LE(stats.connections.peakOpen, 4u);
    EXPECT_GE(stats.connections.timedOut, 2u);

    // Headers over the limit, a chunked body, and a body over the limit announced with Expect.
    RawConnection longHeaders(port);
    longHeaders.send("GET / HTTP/1.1\r\n" + host + "X-Long: " + std::string(20000, 'a') + "\r\n\r\n");
    const std::string tooLong = longHeaders.receiveUntilClosed(10);
    EXPECT_EQ(tooLong.rfind("HTTP/1.1 431", 0), 0u) << tooLong;
    RawConnection chunked(port);
    chunked.send("POST /api/check HTTP/1.1\r\n" + host + "Transfer-Encoding: chunked\r\n\r\n");
    EXPECT_EQ(chunked.receiveUntilClosed(10).rfind("HTTP/1.1 411", 0), 0u);
    RawConnection expecting(port);
    expecting.send("POST /api/check HTTP/1.1\r\n" + host +
                   "Content-Type: application/json\r\nContent-Length: 999999999\r\nExpect: 100-continue\r\n\r\n");
    EXPECT_EQ(expecting.receiveUntilClosed(10).rfind("HTTP/1.1 413", 0), 0u);
    // Two requests in one write (pipelined) get two answers, in order.
    RawConnection pipelined(port);
    const std::string body = json{{"q", kBoomInRack}}.dump();
    const std::string request = "POST /api/check HTTP/1.1\r\n" + host +
                                "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                                "\r\n\r\n" + body;
    pipelined.send(request + "GET /api/nothing HTTP/1.1\r\n" + host + "Connection: close\r\n\r\n");
    const std::string answers = pipelined.receiveUntilClosed(30);
    EXPECT_EQ(answers.rfind("HTTP/1.1 200", 0), 0u) << answers.substr(0, 200);
    EXPECT_NE(answers.find("HTTP/1.1 404"), std::string::npos) << answers.substr(0, 200);
}

/** \brief The load test (issue 32): 64 idle connections held open while 8 clients send 500 check
    requests each (free and colliding states, every tenth request malformed); every request gets
    its answer; p99 latency printed; resident memory after the run within 10 % of its value after
    warm-up; no thread or descriptor left behind. $RASTERCHECK_VIEW_LOAD_SCALE shrinks it. */
TEST_F(ViewServerTest, LoadWithIdleConnectionsEveryRequestAnsweredMemoryFlat)
{
    const int clients = 8, requests = rastercheck::test::scaledCount(500, kLoadScale);
    std::mutex mutex;
    const auto run = [&](int perClient, std::vector<double> *latencies)
    {
        return fromClients(
            clients, perClient,
            [&](httplib::Client &client, int t, int r)
            {
                const int kind = (t + r) % 10;  // 0: malformed; odd: colliding; else free
                const std::string body =
                    kind == 0 ? R"({"q": [0, 0, 0,)" : checkBody(kind % 2 ? kBoomInRack : kFree).dump();
                const auto start = std::chrono::steady_clock::now();
                httplib::Result result = client.Post("/api/check", body, "application/json");
                const double milliseconds =
                    std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
                if (latencies)
                {
                    std::lock_guard<std::mutex> lock(mutex);
                    latencies->push_back(milliseconds);
                }
                if (!result)
                    return false;
                if (kind == 0)
                    return result->status == 400;
                return result->status == 200 && json::parse(result->body)["valid"] == (kind % 2 == 0);
            });
    };
    using rastercheck::test::ProcessFootprint;
    const ProcessFootprint before = ProcessFootprint::now();
    std::vector<std::unique_ptr<RawConnection>> idle;
    for (int i = 0; i < 64; ++i)
        idle.push_back(std::make_unique<RawConnection>(port_));
    EXPECT_EQ(run(std::max(1, requests / 5), nullptr), clients * std::max(1, requests / 5));  // warm-up
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the clients' connections closed
    const ProcessFootprint warm = ProcessFootprint::now();
    std::vector<double> latencies;
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(run(requests, &latencies), clients * requests);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const ProcessFootprint after = ProcessFootprint::now();
    const double p50 = percentile(latencies, 0.5), p99 = percentile(latencies, 0.99);
    std::cout << clients << " clients x " << requests << " requests with 64 idle connections: " << seconds
              << " s, p50 " << p50 << " ms, p99 " << p99 << " ms, max " << percentile(latencies, 1.0)
              << " ms; resident " << warm.residentBytes / 1048576.0 << " -> " << after.residentBytes / 1048576.0
              << " MiB\n";
    RecordProperty("p99_ms", std::to_string(p99));
    EXPECT_TRUE(rastercheck::test::footprintFlat(warm, after));
    if (fullSize())
    {
        EXPECT_LT(p99, 250.0) << "the target is 50 ms; this bound leaves room for a loaded CI machine";
    }
    // Every connection closed again, no thread or descriptor left behind.
    idle.clear();
    EXPECT_EQ(openConnectionsAfterClientsLeft(), 0u);
    const ProcessFootprint end = ProcessFootprint::now();
    EXPECT_EQ(end.threads, before.threads);
    EXPECT_EQ(end.descriptors, before.descriptors);
}

/** \brief Long-running use: 10^4 requests (single states, batches, the model, rasters, bad ones)
    on one server; resident memory within 10 % of its value after warm-up. */
TEST_F(ViewServerTest, TenThousandRequestsKeepMemoryFlat)
{
    const int total = rastercheck::test::scaledCount(10000, kLoadScale), clients = 2;
    std::string raster = "/api/raster?q=";
    for (std::size_t i = 0; i < kBoomInRack.size(); ++i)
        raster += (i ? "," : "") + std::to_string(kBoomInRack[i]);
    const std::string batch = json{{"states", {kFree, kBoomInRack, kStart, kGoal}}}.dump();
    const auto run = [&](int from, int to)
    {
        return fromClients(clients, (to - from) / clients,
                           [&](httplib::Client &client, int t, int i)
                           {
                               const int r = from + i * clients + t;
                               const auto send = [&]
                               {
                                   switch (r % 200)
                                   {
                                       case 0:
                                           return client.Get(raster.c_str());
                                       case 1:
                                           return client.Get("/api/model");
                                       case 2:
                                           return client.Post("/api/check", "{\"q\": [1, 2", "application/json");
                                       default:
                                           return client.Post("/api/check", r % 2 ? batch : checkBody(kFree).dump(),
                                                              "application/json");
                                   }
                               };
                               const httplib::Result result = send();
                               return result && (result->status == 200 || (r % 200 == 2 && result->status == 400));
                           });
    };
    const int warmUp = std::max(clients, total / 5 / clients * clients);
    EXPECT_EQ(run(0, warmUp), warmUp);
    EXPECT_EQ(openConnectionsAfterClientsLeft(), 0u);
    const auto warm = rastercheck::test::ProcessFootprint::now();
    EXPECT_EQ(run(warmUp, total), (total - warmUp) / clients * clients);
    EXPECT_EQ(openConnectionsAfterClientsLeft(), 0u);
    const auto after = rastercheck::test::ProcessFootprint::now();
    std::cout << total << " requests: resident " << warm.residentBytes / 1048576.0 << " MiB after " << warmUp
              << ", " << after.residentBytes / 1048576.0 << " MiB after all\n";
    EXPECT_TRUE(rastercheck::test::footprintFlat(warm, after));
}

TEST_F(ViewServerTest, PlanFindsALiftWhoseEveryStateIsValid)
{
    // The content's start and goal (the lift), BatchRRTConnect by default, on certified edges.
    const json answer = postTo("/api/plan", json{{"time_limit", 30}}.dump());
    ASSERT_EQ(answer["solved"], true) << answer.dump();
    EXPECT_EQ(answer["planner"], "BatchRRTConnect");
    const json &path = answer["path"];
    ASSERT_GE(path.size(), 2u);
    for (std::size_t i = 0; i < kStart.size(); ++i)
    {
        EXPECT_NEAR(path.front()[i].get<double>(), kStart[i], 1e-9);
        EXPECT_NEAR(path.back()[i].get<double>(), kGoal[i], 1e-9);
    }
    const json verdicts = post(json{{"states", path}}.dump());
    EXPECT_EQ(verdicts["valid"], json(std::vector<bool>(path.size(), true))) << path.dump();
    EXPECT_GT(answer["seconds"].get<double>(), 0.0);
}

TEST_F(ViewServerTest, BadPlanRequestsAreRefusedAndAnInvalidStartIsNamed)
{
    expectRefused(postTo("/api/plan", R"({"planner": "warpdrive"})", 400), "warpdrive");
    expectRefused(postTo("/api/plan", R"({"planner": 3})", 400), "planner must be a name");
    expectRefused(postTo("/api/plan", R"({"time_limit": -1})", 400), "time_limit must be a number of seconds in (0, 60]");
    expectRefused(postTo("/api/plan", R"({"time_limit": 1000})", 400), "time_limit must be");
    expectRefused(postTo("/api/plan", R"({"time_limit": "1"})", 400), "time_limit must be");
    expectRefused(postTo("/api/plan", R"({"start": [1, 2]})", 400), "start has 2 values");
    expectRefused(postTo("/api/plan", R"({"goal": "up"})", 400), "goal must be an array");
    expectRefused(postTo("/api/plan", R"({"goals": []})", 400), "unknown field \"goals\"");
    expectRefused(postTo("/api/plan", "[1]", 400), "expected an object");
    expectRefused(postTo("/api/plan", "{", 400), "malformed JSON");
    // A start in the rack is a question with an answer: no path, and why.
    const json answer = postTo("/api/plan", json{{"start", kBoomInRack}}.dump());
    EXPECT_EQ(answer["solved"], false);
    EXPECT_TRUE(answer["path"].empty());
    EXPECT_NE(answer["message"].get<std::string>().find("the start is invalid: "), std::string::npos) << answer;
}

TEST(ViewServerPlan, PandaPlanOfAMotionBenchMakerProblemHasOnlyValidStates)
{
    RASTERCHECK_REQUIRE_DATA(root);
    const rc::Problem problem = rastercheck::test::pandaProblem(root, "bookshelf_small");
    const rc::MotionPlanRequest request =
        rc::loadMoveItRequest(root + "/mbm/panda/problems/bookshelf_small_panda/request0001.yaml");
    const rc::ompl::StateMapping mapping(problem.robot);
    rc::view::ViewContent content;
    content.start = rc::ompl::configurationFromJoints(mapping, request.startJoints, "start");
    content.goal = rc::ompl::configurationFromJoints(mapping, request.goalJoints, "goal");
    rc::view::ViewServerOptions options;
    options.port = 0;
    options.webDir = rastercheck::test::sourcePath("src/view/web");
    options.threeDir = options.webDir;
    rc::view::ViewServer server(problem, content, options);
    const int port = server.bind();
    server.start();
    httplib::Client client("127.0.0.1", port);
    client.set_read_timeout(120, 0);
    httplib::Result result = client.Post("/api/plan", R"({"time_limit": 30})", "application/json");
    ASSERT_TRUE(result);
    ASSERT_EQ(result->status, 200) << result->body;
    const json answer = json::parse(result->body);
    ASSERT_EQ(answer["solved"], true) << answer.dump();
    // The path's states and 10 states on each of its motions (the Panda's joints move linearly).
    const json &path = answer["path"];
    json dense = json::array();
    for (std::size_t r = 0; r + 1 < path.size(); ++r)
        for (int k = 0; k < 10; ++k)
        {
            std::vector<double> q(mapping.numCoordinates());
            for (std::size_t i = 0; i < q.size(); ++i)
                q[i] = path[r][i].get<double>() + (path[r + 1][i].get<double>() - path[r][i].get<double>()) * k / 10.0;
            dense.push_back(q);
        }
    dense.push_back(path.back());
    result = client.Post("/api/check", json{{"states", dense}}.dump(), "application/json");
    ASSERT_TRUE(result);
    ASSERT_EQ(result->status, 200) << result->body;
    EXPECT_EQ(json::parse(result->body)["valid"], json(std::vector<bool>(dense.size(), true)));
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
        std::string(RASTERCHECK_CLI) + " view " + problem + " --path " + path + " --request " +
        rastercheck::test::sourcePath("robots/sites/plant_lift.yaml") + " --port 0 > " + output +
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
}
