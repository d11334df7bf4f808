// The frame rate the overlay shows: frames completed over the last second of frame end times, so it is
// what the machine really draws (never an average of 1/dt seeded by a near-zero first interval).
#pragma once

#include <cstddef>
#include <deque>
#include <optional>

namespace terrain {

class FrameRateMeter {
public:
    /// Seconds of frame end times the rate is measured over.
    static constexpr double kWindowSeconds = 1.0;

    /// Records that a frame ended at `seconds` (any monotonic clock, non-decreasing).
    void frameEnded(double seconds);
    /// Frames per second over the window: (ends in the window - 1) / (last end - first end). Empty until
    /// two frames have ended.
    std::optional<double> framesPerSecond() const;
    /// The mean frame time over the same frames, seconds; empty until two frames have ended.
    std::optional<double> meanFrameSeconds() const;

private:
    std::deque<double> mEnds;
};

}  // namespace terrain
