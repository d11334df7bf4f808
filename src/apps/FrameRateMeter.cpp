#include "apps/FrameRateMeter.h"

#include "core/Check.h"

namespace terrain {

void FrameRateMeter::frameEnded(double seconds)
{
    TERRAIN_EXPECTS(mEnds.empty() || seconds >= mEnds.back(), "FrameRateMeter: frame end times must not decrease");
    mEnds.push_back(seconds);
    // Keep one end at or before the window's start, so a frame slower than the window still measures.
    while (mEnds.size() > 2 && mEnds[1] <= seconds - kWindowSeconds) {
        mEnds.pop_front();
    }
}

std::optional<double> FrameRateMeter::meanFrameSeconds() const
{
    if (mEnds.size() < 2 || mEnds.back() <= mEnds.front()) {
        return std::nullopt;
    }
    return (mEnds.back() - mEnds.front()) / static_cast<double>(mEnds.size() - 1);
}

std::optional<double> FrameRateMeter::framesPerSecond() const
{
    auto mean = meanFrameSeconds();
    if (!mean) {
        return std::nullopt;
    }
    return 1.0 / *mean;
}

}  // namespace terrain
