#include "view/ConnectionLoop.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include <httplib.h>
#include "rastercheck/core/Text.h"

namespace rastercheck::view
{
namespace
{
using Clock = std::chrono::steady_clock;

/** \brief A client connection and what it has sent that is not answered yet. */
struct Connection
{
    int fd = -1;
    std::string peerIp;
    int peerPort = 0;
    std::string buffer;          ///< bytes received, not yet answered (a next request may follow)
    std::size_t scanned = 0;     ///< bytes of buffer searched for the end of the header block
    std::size_t headerEnd = 0;   ///< end of the next request's header block; 0 while it is incomplete
    std::size_t requestEnd = 0;  ///< end of the next request (headers and body), once headerEnd is known
    std::size_t discard = 0;     ///< body bytes still to read and drop (a body over the limit)
    bool closeAfter = false;     ///< answer this request, then close (its body was dropped)
    Clock::time_point deadline;  ///< idle or request timeout, whichever applies
    Clock::time_point idleSince;

    bool idle() const { return buffer.empty() && discard == 0; }
    bool complete() const { return headerEnd != 0 && discard == 0 && buffer.size() >= requestEnd; }
    /** \brief Forgets the request just answered; keeps what followed it. */
    void consumeRequest()
    {
        buffer.erase(0, std::min(requestEnd, buffer.size()));
        scanned = headerEnd = requestEnd = 0;
    }
};

void closeSocket(int fd)
{
    ::shutdown(fd, SHUT_RDWR);
    ::close(fd);
}

/** \brief An answer from the loop itself, for a request no handler sees; best effort (a short
    answer fits the socket's send buffer), the connection is closed next. */
void sendRefusal(int fd, int status, const char *reason, const std::string &message)
{
    const std::string body = "{\"error\": \"" + message + "\"}";
    const std::string text = "HTTP/1.1 " + std::to_string(status) + " " + reason +
                             "\r\nContent-Type: application/json\r\nCache-Control: no-store\r\nContent-Length: " +
                             std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
    [[maybe_unused]] const ssize_t sent = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    // Closing with unread input resets the connection, and the client may lose the answer: read
    // what has arrived (the rest of headers over the limit, say) first.
    char chunk[16 * 1024];
    for (int i = 0; i < 64 && ::recv(fd, chunk, sizeof chunk, MSG_DONTWAIT) > 0; ++i)
    {
    }
}

/** \brief The request as httplib reads it: the bytes of one complete request from the loop's
    buffer; answers go to the socket, waiting at most the write timeout for the client to read. */
class BufferedStream : public httplib::Stream
{
public:
    BufferedStream(Connection &connection, std::chrono::milliseconds writeTimeout)
        : connection_(connection), end_(connection.requestEnd), writeTimeout_(writeTimeout)
    {
    }

    bool is_readable() const override { return position_ < end_; }
    bool is_writable() const override { return true; }

    ssize_t read(char *ptr, size_t size) override
    {
        const std::size_t n = std::min(size, end_ - std::min(position_, end_));
        std::copy_n(connection_.buffer.data() + position_, n, ptr);
        position_ += n;
        return static_cast<ssize_t>(n);
    }

    ssize_t write(const char *ptr, size_t size) override
    {
        const Clock::time_point deadline = Clock::now() + writeTimeout_;
        std::size_t sent = 0;
        while (sent < size)
        {
            const ssize_t n = ::send(connection_.fd, ptr + sent, size - sent, MSG_NOSIGNAL);
            if (n > 0)
            {
                sent += static_cast<std::size_t>(n);
                continue;
            }
            if (n < 0 && errno == EINTR)
                continue;
            if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            {
                const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
                if (left.count() <= 0)
                    return -1;
                pollfd writable{connection_.fd, POLLOUT, 0};
                ::poll(&writable, 1, static_cast<int>(left.count()));
                continue;
            }
            return -1;
        }
        return static_cast<ssize_t>(size);
    }

    void get_remote_ip_and_port(std::string &ip, int &port) const override
    {
        ip = connection_.peerIp;
        port = connection_.peerPort;
    }

    void get_local_ip_and_port(std::string &ip, int &port) const override
    {
        sockaddr_storage address{};
        socklen_t length = sizeof address;
        ip.clear();
        port = 0;
        if (::getsockname(connection_.fd, reinterpret_cast<sockaddr *>(&address), &length) == 0)
            describeAddress(address, ip, port);
    }

    socket_t socket() const override { return connection_.fd; }

    static void describeAddress(const sockaddr_storage &address, std::string &ip, int &port)
    {
        char text[INET6_ADDRSTRLEN] = {};
        if (address.ss_family == AF_INET)
        {
            const auto &v4 = reinterpret_cast<const sockaddr_in &>(address);
            ::inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
            port = ntohs(v4.sin_port);
        }
        else if (address.ss_family == AF_INET6)
        {
            const auto &v6 = reinterpret_cast<const sockaddr_in6 &>(address);
            ::inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
            port = ntohs(v6.sin6_port);
        }
        ip = text;
    }

private:
    Connection &connection_;
    std::size_t position_ = 0;
    std::size_t end_;
    std::chrono::milliseconds writeTimeout_;
};
}  // namespace

struct ConnectionLoop::Impl
{
    Impl(int listeningSocket, ConnectionLimits limitsIn, Handler handleIn)
        : listenFd(listeningSocket), limits(limitsIn), handle(std::move(handleIn)), wakeFd(::eventfd(0, EFD_CLOEXEC))
    {
        ::fcntl(listenFd, F_SETFL, ::fcntl(listenFd, F_GETFL) | O_NONBLOCK);
        // httplib listens with a backlog of 5; clients that connect together (a page's parallel
        // requests, the load test's clients) would wait a second for a SYN retry past it.
        ::listen(listenFd, 128);
    }

    ~Impl()
    {
        if (listenFd >= 0)
            ::close(listenFd);
        if (wakeFd >= 0)
            ::close(wakeFd);
    }

    void wake() const
    {
        const std::uint64_t one = 1;
        [[maybe_unused]] const ssize_t n = ::write(wakeFd, &one, sizeof one);
    }

    std::size_t openNow() const { return waiting.size() + busy.load(); }

    void closeConnection(std::unique_ptr<Connection> connection)
    {
        closeSocket(connection->fd);
        std::lock_guard<std::mutex> lock(statsMutex);
        --stats.open;
    }

    /** \brief Reads what \a connection has sent; false when it closed or failed. Bytes of a body
        over the limit are dropped as they come. */
    bool receive(Connection &connection)
    {
        char chunk[64 * 1024];
        for (;;)
        {
            const ssize_t n = ::recv(connection.fd, chunk, sizeof chunk, 0);
            if (n == 0)
                return false;
            if (n < 0)
                return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
            const Clock::time_point now = Clock::now();
            if (connection.idle())
                connection.deadline = now + limits.requestTimeout;  // the first byte of a request
            std::size_t used = 0;
            if (connection.discard > 0)
            {
                used = std::min<std::size_t>(connection.discard, static_cast<std::size_t>(n));
                connection.discard -= used;
            }
            connection.buffer.append(chunk + used, static_cast<std::size_t>(n) - used);
            // Enough for parse() to go on: the rest stays in the socket (poll() wakes again).
            if (connection.headerEnd == 0 ? connection.buffer.size() > limits.maxHeaderBytes : connection.complete())
                return true;
        }
    }

    enum class Parse
    {
        Incomplete,
        Complete,
        Refused  ///< answered by the loop; close the connection
    };

    /** \brief Finds the next request's end in the buffer: the header block's end, then the body's
        length from Content-Length. */
    Parse parse(Connection &connection) const
    {
        if (connection.headerEnd == 0)
        {
            const std::size_t from = connection.scanned >= 3 ? connection.scanned - 3 : 0;
            const std::size_t end = connection.buffer.find("\r\n\r\n", from);
            if (end == std::string::npos || end + 4 > limits.maxHeaderBytes)
            {
                connection.scanned = connection.buffer.size();
                if (connection.buffer.size() > limits.maxHeaderBytes)
                {
                    sendRefusal(connection.fd, 431, "Request Header Fields Too Large",
                                "request headers over the limit of " + std::to_string(limits.maxHeaderBytes) +
                                    " bytes");
                    return Parse::Refused;
                }
                return Parse::Incomplete;
            }
            connection.headerEnd = end + 4;
            unsigned long long length = 0;
            bool expectContinue = false;
            std::size_t line = connection.buffer.find("\r\n") + 2;
            while (line < end + 2)
            {
                const std::size_t lineEnd = connection.buffer.find("\r\n", line);
                const std::size_t colon = connection.buffer.find(':', line);
                if (colon < lineEnd)
                {
                    const std::string name = lowerCase(connection.buffer.substr(line, colon - line));
                    const std::string value = trim(connection.buffer.substr(colon + 1, lineEnd - colon - 1));
                    if (name == "content-length")
                    {
                        if (value.empty() || value.size() > 18 ||
                            value.find_first_not_of("0123456789") != std::string::npos)
                        {
                            sendRefusal(connection.fd, 400, "Bad Request", "Content-Length is not a number");
                            return Parse::Refused;
                        }
                        length = std::stoull(value);
                    }
                    else if (name == "transfer-encoding")
                    {
                        sendRefusal(connection.fd, 411, "Length Required",
                                    "send the body with a Content-Length (no Transfer-Encoding)");
                        return Parse::Refused;
                    }
                    else if (name == "expect" && lowerCase(value) == "100-continue")
                    {
                        // Answered here, when the loop starts waiting for the body; the header is
                        // renamed so that httplib does not answer it a second time.
                        expectContinue = true;
                        connection.buffer.replace(line, 6, "X-Seen");
                    }
                }
                line = lineEnd + 2;
            }
            if (length > limits.maxBodyBytes)
            {
                if (expectContinue)
                {
                    sendRefusal(connection.fd, 413, "Payload Too Large",
                                "request body over the limit of " + std::to_string(limits.maxBodyBytes) + " bytes");
                    return Parse::Refused;
                }
                // Read and drop the body (closing with it unread would reset the connection before
                // the client reads the 413); httplib answers 413 from the Content-Length.
                const std::size_t received = std::min<std::size_t>(connection.buffer.size() - connection.headerEnd,
                                                                   static_cast<std::size_t>(length));
                connection.buffer.resize(connection.headerEnd);
                connection.discard = static_cast<std::size_t>(length) - received;
                connection.requestEnd = connection.headerEnd;
                connection.closeAfter = true;
            }
            else
            {
                connection.requestEnd = connection.headerEnd + static_cast<std::size_t>(length);
                if (expectContinue && connection.buffer.size() < connection.requestEnd)
                {
                    static const char continueLine[] = "HTTP/1.1 100 Continue\r\n\r\n";
                    [[maybe_unused]] const ssize_t sent =
                        ::send(connection.fd, continueLine, sizeof continueLine - 1, MSG_NOSIGNAL | MSG_DONTWAIT);
                }
            }
        }
        return connection.complete() ? Parse::Complete : Parse::Incomplete;
    }

    /** \brief Hands a complete request to the workers, or keeps waiting, or closes. */
    void advance(std::unique_ptr<Connection> connection)
    {
        switch (parse(*connection))
        {
            case Parse::Refused:
                closeConnection(std::move(connection));
                return;
            case Parse::Incomplete:
            {
                const int fd = connection->fd;
                waiting[fd] = std::move(connection);
                return;
            }
            case Parse::Complete:
            {
                ++busy;
                {
                    std::lock_guard<std::mutex> lock(jobsMutex);
                    jobs.push_back(std::move(connection));
                }
                jobsReady.notify_one();
                return;
            }
        }
    }

    void acceptAll()
    {
        for (;;)
        {
            sockaddr_storage address{};
            socklen_t length = sizeof address;
            const int fd = ::accept4(listenFd, reinterpret_cast<sockaddr *>(&address), &length,
                                     SOCK_NONBLOCK | SOCK_CLOEXEC);
            if (fd < 0)
            {
                if (errno == EINTR || errno == ECONNABORTED)
                    continue;
                // EAGAIN: none left. EMFILE / ENFILE: out of descriptors; the pending ones wait
                // in the backlog until a connection closes (poll() wakes at the next timeout).
                if (errno == EMFILE || errno == ENFILE)
                    acceptPausedUntil = Clock::now() + std::chrono::milliseconds(50);
                return;
            }
            const Clock::time_point now = Clock::now();
            if (openNow() >= limits.maxConnections && !evictIdlest())
            {
                sendRefusal(fd, 503, "Service Unavailable",
                            "too many connections (" + std::to_string(limits.maxConnections) + ")");
                closeSocket(fd);
                std::lock_guard<std::mutex> lock(statsMutex);
                ++stats.refused;
                continue;
            }
            const int yes = 1;
            // An answer goes out in two writes (head, body); with Nagle's algorithm the second
            // waits for the client's delayed ACK (40 ms per check in Chromium).
            ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
            auto connection = std::make_unique<Connection>();
            connection->fd = fd;
            BufferedStream::describeAddress(address, connection->peerIp, connection->peerPort);
            connection->deadline = now + limits.idleTimeout;
            connection->idleSince = now;
            waiting[fd] = std::move(connection);
            std::lock_guard<std::mutex> lock(statsMutex);
            ++stats.accepted;
            ++stats.open;
            stats.peakOpen = std::max(stats.peakOpen, stats.open);
        }
    }

    /** \brief Closes the connection idle the longest; false when none is idle. */
    bool evictIdlest()
    {
        auto idlest = waiting.end();
        for (auto it = waiting.begin(); it != waiting.end(); ++it)
            if (it->second->idle() && (idlest == waiting.end() || it->second->idleSince < idlest->second->idleSince))
                idlest = it;
        if (idlest == waiting.end())
            return false;
        std::unique_ptr<Connection> connection = std::move(idlest->second);
        waiting.erase(idlest);
        closeConnection(std::move(connection));
        std::lock_guard<std::mutex> lock(statsMutex);
        ++stats.evicted;
        return true;
    }

    void takeReturned()
    {
        std::vector<std::unique_ptr<Connection>> back;
        {
            std::lock_guard<std::mutex> lock(jobsMutex);
            back.swap(returned);
        }
        const Clock::time_point now = Clock::now();
        for (std::unique_ptr<Connection> &connection : back)
        {
            --busy;
            connection->idleSince = now;
            connection->deadline = now + (connection->idle() ? limits.idleTimeout : limits.requestTimeout);
            advance(std::move(connection));
        }
    }

    void closeExpired()
    {
        const Clock::time_point now = Clock::now();
        for (auto it = waiting.begin(); it != waiting.end();)
        {
            if (now < it->second->deadline)
            {
                ++it;
                continue;
            }
            if (!it->second->idle())
                sendRefusal(it->second->fd, 408, "Request Timeout",
                            "the request did not arrive whole within " +
                                std::to_string(limits.requestTimeout.count()) + " ms");
            std::unique_ptr<Connection> connection = std::move(it->second);
            it = waiting.erase(it);
            closeConnection(std::move(connection));
            std::lock_guard<std::mutex> lock(statsMutex);
            ++stats.timedOut;
        }
    }

    void run()
    {
        std::vector<pollfd> fds;
        while (!stopping.load())
        {
            takeReturned();
            const Clock::time_point now = Clock::now();
            Clock::time_point next = now + std::chrono::seconds(1);
            fds.clear();
            fds.push_back({wakeFd, POLLIN, 0});
            const bool accepting = now >= acceptPausedUntil;
            fds.push_back({accepting ? listenFd : -1, POLLIN, 0});
            if (!accepting)
                next = std::min(next, acceptPausedUntil);
            for (const auto &[fd, connection] : waiting)
            {
                fds.push_back({fd, POLLIN, 0});
                next = std::min(next, connection->deadline);
            }
            const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - now).count() + 1;
            if (::poll(fds.data(), fds.size(), static_cast<int>(std::max<long long>(wait, 0))) < 0 &&
                errno != EINTR)
                break;
            if (fds[0].revents)
            {
                std::uint64_t count = 0;
                [[maybe_unused]] const ssize_t n = ::read(wakeFd, &count, sizeof count);
            }
            if (fds[1].revents)
                acceptAll();
            for (std::size_t i = 2; i < fds.size(); ++i)
            {
                if (!fds[i].revents)
                    continue;
                auto it = waiting.find(fds[i].fd);
                if (it == waiting.end())
                    continue;
                std::unique_ptr<Connection> connection = std::move(it->second);
                waiting.erase(it);
                if (receive(*connection))
                    advance(std::move(connection));
                else
                    closeConnection(std::move(connection));
            }
            closeExpired();
        }
        for (auto &[fd, connection] : waiting)
            closeConnection(std::move(connection));
        waiting.clear();
    }

    void work()
    {
        for (;;)
        {
            std::unique_ptr<Connection> connection;
            {
                std::unique_lock<std::mutex> lock(jobsMutex);
                jobsReady.wait(lock, [&] { return !jobs.empty() || stopping.load(); });
                if (jobs.empty())
                    return;
                connection = std::move(jobs.front());
                jobs.pop_front();
            }
            bool keep = !stopping.load();
            if (keep)
            {
                BufferedStream stream(*connection, limits.writeTimeout);
                bool closed = false;
                const bool answered = handle(stream, connection->closeAfter, closed);
                {
                    std::lock_guard<std::mutex> lock(statsMutex);
                    ++stats.requests;
                }
                keep = answered && !closed && !connection->closeAfter;
            }
            if (!keep)
            {
                --busy;
                closeConnection(std::move(connection));
                continue;
            }
            connection->consumeRequest();
            {
                std::lock_guard<std::mutex> lock(jobsMutex);
                returned.push_back(std::move(connection));
            }
            wake();
        }
    }

    int listenFd;
    ConnectionLimits limits;
    Handler handle;
    int wakeFd;
    std::atomic<bool> stopping{false};
    std::atomic<std::size_t> busy{0};  ///< connections with the workers (queued, answered, or returned)
    Clock::time_point acceptPausedUntil{};
    std::unordered_map<int, std::unique_ptr<Connection>> waiting;  ///< the loop thread's alone

    std::mutex jobsMutex;
    std::condition_variable jobsReady;
    std::deque<std::unique_ptr<Connection>> jobs;
    std::vector<std::unique_ptr<Connection>> returned;

    mutable std::mutex statsMutex;
    ConnectionStats stats;

    std::thread loopThread;
    std::vector<std::thread> workers;
    bool started = false;
    bool stopped = false;
};

ConnectionLoop::ConnectionLoop(int listeningSocket, ConnectionLimits limits, Handler handle)
    : impl_(std::make_unique<Impl>(listeningSocket, limits, std::move(handle)))
{
}

ConnectionLoop::~ConnectionLoop()
{
    stop();
}

void ConnectionLoop::start()
{
    if (impl_->started || impl_->stopped)
        return;
    impl_->started = true;
    for (int i = 0; i < std::max(1, impl_->limits.workers); ++i)
        impl_->workers.emplace_back([this] { impl_->work(); });
    impl_->loopThread = std::thread([this] { impl_->run(); });
}

void ConnectionLoop::stop()
{
    if (impl_->stopped)
        return;
    impl_->stopped = true;
    impl_->stopping = true;
    impl_->wake();
    if (impl_->loopThread.joinable())
        impl_->loopThread.join();
    impl_->jobsReady.notify_all();
    for (std::thread &worker : impl_->workers)
        worker.join();
    // Connections the workers gave back after the loop ended, or never took.
    for (std::unique_ptr<Connection> &connection : impl_->returned)
        impl_->closeConnection(std::move(connection));
    for (std::unique_ptr<Connection> &connection : impl_->jobs)
        impl_->closeConnection(std::move(connection));
    impl_->returned.clear();
    impl_->jobs.clear();
    ::close(impl_->listenFd);
    impl_->listenFd = -1;
}

ConnectionStats ConnectionLoop::stats() const
{
    std::lock_guard<std::mutex> lock(impl_->statsMutex);
    return impl_->stats;
}
}  // namespace rastercheck::view
