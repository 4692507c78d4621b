#pragma once
// The viewer's connections: one thread waits on every socket (poll) and reads each request whole;
// a few worker threads answer complete requests. A connection that sends nothing, or sends slowly,
// holds no worker: cpp-httplib's own listen() gives each connection a pool thread that waits for
// it (5 s per idle keep-alive connection by default), so 8 idle browser connections stalled the
// viewer's 8 threads (issue 32).

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>

namespace httplib
{
class Stream;
}

namespace rastercheck::view
{
/** \brief Limits of the connection loop (ViewServerOptions carries them). */
struct ConnectionLimits
{
    /** \brief Connections open at once. A new one past it closes the connection idle the longest;
        when none is idle it is answered 503 and closed. */
    std::size_t maxConnections = 128;
    /** \brief A connection that has sent no byte of a next request for this long is closed. */
    std::chrono::milliseconds idleTimeout{5000};
    /** \brief A request (headers and body) must arrive whole within this after its first byte;
        else 408 and the connection is closed (a client that trickles bytes holds nothing longer). */
    std::chrono::milliseconds requestTimeout{10000};
    /** \brief An answer that the client does not read for this long is dropped with its connection. */
    std::chrono::milliseconds writeTimeout{5000};
    /** \brief Threads that answer complete requests. */
    int workers = 4;
    /** \brief Largest header block; a larger one is answered 431. */
    std::size_t maxHeaderBytes = 16 * 1024;
    /** \brief Largest body read; the body of a larger request is read and dropped, and the request
        goes to the handler without it (httplib answers 413 from its Content-Length). */
    std::size_t maxBodyBytes = std::size_t(8) << 20;
};

/** \brief Counts of the loop since start (ViewServer::stats()). */
struct ConnectionStats
{
    std::size_t open = 0;       ///< connections open now
    std::size_t peakOpen = 0;   ///< most open at once
    std::size_t accepted = 0;   ///< connections accepted
    std::size_t evicted = 0;    ///< idle connections closed to make room for a new one
    std::size_t refused = 0;    ///< new connections answered 503 (no room)
    std::size_t timedOut = 0;   ///< connections closed by the idle or request timeout
    std::size_t requests = 0;   ///< requests handed to the handler
};

/** \brief Serves a listening socket until stop(). \a handle answers one complete request read from
    the stream (httplib::Server::process_request); it is called on the worker threads. */
class ConnectionLoop
{
public:
    using Handler = std::function<bool(httplib::Stream &stream, bool closeConnection, bool &connectionClosed)>;

    /** \brief Takes \a listeningSocket (bound and listening; closed by stop()). */
    ConnectionLoop(int listeningSocket, ConnectionLimits limits, Handler handle);
    /** \brief stop(). */
    ~ConnectionLoop();
    ConnectionLoop(const ConnectionLoop &) = delete;
    ConnectionLoop &operator=(const ConnectionLoop &) = delete;

    /** \brief Starts the loop's thread and the workers; returns at once. */
    void start();
    /** \brief Closes the listening socket and every connection, lets the workers finish the
        requests they are answering, and joins every thread. Idempotent; not from a handler. */
    void stop();
    ConnectionStats stats() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
}  // namespace rastercheck::view
