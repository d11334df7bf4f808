// Client/server node loading (paper 3.2.15) with the request limit of 3.4.4.
#include "lod/NodeServer.h"

#include <algorithm>

namespace terrain {

NodeServer::NodeServer(NodeSource& source, Options options) : mSource(source), mOptions(options)
{
    mQueue.reserve(mOptions.queueLimit);
    for (int i = 0; i < mOptions.workers; ++i) {
        mWorkers.emplace_back([this] { workerLoop(); });
    }
}

NodeServer::~NodeServer()
{
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
        mStats.cancelled += mQueue.size();
        mQueue.clear();
    }
    mWork.notify_all();
    for (auto& worker : mWorkers) {
        worker.join();
    }
}

void NodeServer::submit(std::span<const LoadRequest> wanted)
{
    std::unique_lock lock(mMutex);
    // Cancel what the traversal no longer asks for.
    auto isWanted = [&](const LoadRequest& queued) {
        return std::any_of(wanted.begin(), wanted.end(),
                           [&](const LoadRequest& w) { return w.parent->id == queued.parent->id; });
    };
    auto kept = std::stable_partition(mQueue.begin(), mQueue.end(), isWanted);
    for (auto it = kept; it != mQueue.end(); ++it) {
        mPending.erase(it->parent->id.key());
        ++mStats.cancelled;
    }
    mQueue.erase(kept, mQueue.end());
    // Refresh priorities of kept requests, then admit new ones nearest first.
    for (auto& queued : mQueue) {
        for (const auto& w : wanted) {
            if (w.parent->id == queued.parent->id) {
                queued.distance = w.distance;
            }
        }
    }
    std::vector<const LoadRequest*> fresh;
    for (const auto& w : wanted) {
        const std::uint64_t key = w.parent->id.key();
        if (mPending.count(key) == 0 && mFailed.count(key) == 0) {
            fresh.push_back(&w);
        }
    }
    std::sort(fresh.begin(), fresh.end(), [](const LoadRequest* a, const LoadRequest* b) {
        return a->distance < b->distance || (a->distance == b->distance && a->parent->id.key() < b->parent->id.key());
    });
    bool added = false;
    for (const LoadRequest* w : fresh) {
        if (mQueue.size() >= mOptions.queueLimit) {
            ++mStats.rejected;
            continue;
        }
        mQueue.push_back(*w);
        mPending.insert(w->parent->id.key());
        ++mStats.requested;
        added = true;
    }
    // A worker only moves a request from the queue to in flight; only admitting one here raises the sum.
    mStats.peakPending = std::max(mStats.peakPending, mQueue.size() + mStats.inFlight);
    lock.unlock();
    if (added) {
        mWork.notify_all();
    }
}

bool NodeServer::popNearest(LoadRequest& out)
{
    if (mQueue.empty()) {
        return false;
    }
    auto nearest = std::min_element(mQueue.begin(), mQueue.end(), [](const LoadRequest& a, const LoadRequest& b) {
        return a.distance < b.distance || (a.distance == b.distance && a.parent->id.key() < b.parent->id.key());
    });
    out = std::move(*nearest);
    mQueue.erase(nearest);
    ++mStats.inFlight;
    return true;
}

void NodeServer::load(const LoadRequest& request)
{
    auto children = mSource.loadChildren(*request.parent);
    std::lock_guard lock(mMutex);
    --mStats.inFlight;
    ++mStats.completed;
    if (!children.ok()) {
        ++mStats.failed;
        mFailed.insert(request.parent->id.key());
    }
    mCompleted.push_back(LoadedChildren{request.parent->id, std::move(children)});
    mIdle.notify_all();
}

void NodeServer::workerLoop()
{
    for (;;) {
        LoadRequest request;
        {
            std::unique_lock lock(mMutex);
            mWork.wait(lock, [&] { return mStopping || !mQueue.empty(); });
            if (mStopping) {
                return;
            }
            popNearest(request);
        }
        load(request);
    }
}

std::vector<LoadedChildren> NodeServer::takeCompleted()
{
    std::lock_guard lock(mMutex);
    std::vector<LoadedChildren> out;
    out.swap(mCompleted);
    for (const auto& done : out) {
        mPending.erase(done.parent.key());
    }
    return out;
}

void NodeServer::drain()
{
    if (mOptions.workers == 0) {
        for (;;) {
            LoadRequest request;
            {
                std::lock_guard lock(mMutex);
                if (!popNearest(request)) {
                    return;
                }
            }
            load(request);
        }
    }
    std::unique_lock lock(mMutex);
    mIdle.wait(lock, [&] { return mQueue.empty() && mStats.inFlight == 0; });
}

NodeServerStats NodeServer::stats() const
{
    std::lock_guard lock(mMutex);
    NodeServerStats s = mStats;
    s.queued = mQueue.size();
    return s;
}

}  // namespace terrain
