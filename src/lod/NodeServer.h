// The asynchronous node server (paper 3.2.15, 3.4.4): the render thread asks for the children of nodes
// that need refining; worker threads load (or synthesize) them; finished groups come back through a
// completion queue the render thread drains each frame.
//
// Requests are bounded (`queueLimit`, the paper suggests 4-8), served nearest first, and replaced every
// frame: a queued request the traversal no longer makes is cancelled. A parent whose children failed to
// load is reported once and never requested again, so the parent keeps being drawn.
#pragma once

#include "lod/NodeData.h"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <unordered_set>
#include <vector>

namespace terrain {

/// The traversal wants the children of `parent` (resident, so its data can be shared with the workers).
struct LoadRequest {
    NodePtr parent;
    double distance = 0.0;  ///< camera to the parent's box, metres: the priority (nearest first)
};

/// A finished request: the four children, or why they could not be loaded.
struct LoadedChildren {
    NodeId parent;
    Expected<ChildNodes> children = Error{};
};

struct NodeServerStats {
    std::uint64_t requested = 0;  ///< requests accepted into the queue
    std::uint64_t completed = 0;  ///< groups loaded (successfully or not)
    std::uint64_t cancelled = 0;  ///< queued requests dropped because no longer wanted
    std::uint64_t rejected = 0;   ///< wanted but not queued: the queue was full
    std::uint64_t failed = 0;     ///< groups that could not be loaded
    std::size_t queued = 0;       ///< waiting for a worker now
    std::size_t inFlight = 0;     ///< being loaded now
    /// Most requests queued or loading at once since the server started (sampled where it can grow: after
    /// submit() admits requests), at most queueLimit + workers.
    std::size_t peakPending = 0;
};

class NodeServer {
public:
    struct Options {
        /// Worker threads; 0 runs every load inline in drain(), deterministically, for tests.
        int workers = 1;
        /// Most requests waiting at once.
        std::size_t queueLimit = 8;
    };

    /// `source` must outlive the server.
    NodeServer(NodeSource& source, Options options);
    /// Cancels queued requests, waits for the loads in flight (each is bounded) and joins the workers.
    ~NodeServer();
    NodeServer(const NodeServer&) = delete;
    NodeServer& operator=(const NodeServer&) = delete;

    /// Render thread, once per frame: this frame's requests. Queued requests not among them are cancelled;
    /// new ones (not queued, loading, done or failed already) enter nearest first while there is room.
    void submit(std::span<const LoadRequest> wanted);

    /// Render thread: moves finished groups out, in completion order.
    std::vector<LoadedChildren> takeCompleted();

    /// Waits until nothing is queued or loading (inline mode: does the queued loads now, nearest first).
    void drain();

    NodeServerStats stats() const;

private:
    void workerLoop();
    /// Takes the nearest queued request (caller holds the lock); false if none.
    bool popNearest(LoadRequest& out);
    void load(const LoadRequest& request);

    NodeSource& mSource;
    Options mOptions;
    mutable std::mutex mMutex;
    std::condition_variable mWork;  ///< a request arrived or stopping
    std::condition_variable mIdle;  ///< a load finished
    std::vector<LoadRequest> mQueue;
    std::unordered_set<std::uint64_t> mPending;  ///< parents queued, loading or completed-not-taken
    std::unordered_set<std::uint64_t> mFailed;
    std::vector<LoadedChildren> mCompleted;
    NodeServerStats mStats;
    bool mStopping = false;
    std::vector<std::thread> mWorkers;
};

}  // namespace terrain
