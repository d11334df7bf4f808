// Compares the frames two tengine video-mode runs wrote (frame_NNNNN.png in two directories), frame by frame:
// issue 16's check that visibility_lod changes no visible pixel. Prints, per run and in total, the share of
// identical pixels and the largest 4-connected region of pixels differing by more than LEVELS in some channel,
// with the frame and a pixel of it. Measures and prints; exits 1 only when the directories cannot be compared.
//
//   build/tests/FrameCompare DIR_A DIR_B [--skip N] [--levels 8]
//
// --skip N leaves out the first N frames saved (the runs start with different caches). Run both viewers
// with --set draw_user_interface=false: the overlay prints figures that differ.
#include "core/Parse.h"
#include "heightfield/Image.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {

using namespace terrain;

std::vector<std::string> frameNames(const std::filesystem::path& dir)
{
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        const auto name = entry.path().filename().string();
        if (name.rfind("frame_", 0) == 0 && entry.path().extension() == ".png") {
            names.push_back(name);
        }
    }
    std::sort(names.begin(), names.end());
    return names;
}

int fail(const std::string& message)
{
    std::fprintf(stderr, "FrameCompare: %s\n", message.c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 3) {
        return fail("usage: FrameCompare DIR_A DIR_B [--skip N] [--levels 8]");
    }
    const std::filesystem::path dirA = argv[1], dirB = argv[2];
    long long skip = 0, levels = 8;
    for (int i = 3; i < argc; ++i) {
        const std::string arg = argv[i];
        if ((arg == "--skip" || arg == "--levels") && i + 1 < argc) {
            auto value = parseInteger(argv[++i]);
            if (!value.ok() || *value < 0) {
                return fail(arg + ": '" + argv[i] + "' is not a whole number >= 0");
            }
            (arg == "--skip" ? skip : levels) = *value;
        } else {
            return fail("unknown argument '" + arg + "'");
        }
    }
    std::error_code error;
    if (!std::filesystem::is_directory(dirA, error) || !std::filesystem::is_directory(dirB, error)) {
        return fail("both " + dirA.string() + " and " + dirB.string() + " must be directories");
    }
    const auto names = frameNames(dirA);
    if (names != frameNames(dirB)) {
        return fail(dirA.string() + " and " + dirB.string() + " hold different frame_*.png files");
    }
    if (names.size() <= static_cast<std::size_t>(skip)) {
        return fail("only " + std::to_string(names.size()) + " frames, --skip " + std::to_string(skip));
    }
    std::size_t pixels = 0, identical = 0, worstRegion = 0, framesOver16 = 0, framesUnder995 = 0;
    double worstFrameShare = 1.0;
    std::string worstRegionAt = "-", worstFrame = "-";
    for (std::size_t f = static_cast<std::size_t>(skip); f < names.size(); ++f) {
        auto a = readPngImage(dirA / names[f], 3);
        auto b = readPngImage(dirB / names[f], 3);
        if (!a.ok() || !b.ok()) {
            return fail(!a.ok() ? a.error().message : b.error().message);
        }
        auto d = compareImages(*a, *b, static_cast<int>(levels));
        if (!d.ok()) {
            return fail(names[f] + ": " + d.error().message);
        }
        pixels += d->pixels;
        identical += d->identical;
        const double share = static_cast<double>(d->identical) / static_cast<double>(d->pixels);
        framesUnder995 += share < 0.995 ? 1 : 0;
        if (share < worstFrameShare) {
            worstFrameShare = share;
            worstFrame = names[f];
        }
        framesOver16 += d->largestRegion > 16 ? 1 : 0;
        if (d->largestRegion > worstRegion) {
            worstRegion = d->largestRegion;
            worstRegionAt =
                names[f] + " at " + std::to_string(d->largestRegionX) + "," + std::to_string(d->largestRegionY);
        }
    }
    std::printf("frames compared: %zu (skipped %lld)\n", names.size() - static_cast<std::size_t>(skip), skip);
    std::printf("identical pixels: %.3f%% (worst frame %s: %.3f%%); frames under 99.5%%: %zu\n",
                100.0 * static_cast<double>(identical) / static_cast<double>(pixels), worstFrame.c_str(),
                100.0 * worstFrameShare, framesUnder995);
    std::printf("largest region differing by more than %lld levels: %zu pixels (%s); frames with one over 16: %zu\n",
                levels, worstRegion, worstRegionAt.c_str(), framesOver16);
    return 0;
}
