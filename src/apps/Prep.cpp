// prep: height field -> .map (paper 4.4.1). Argument parsing and reporting only; the work is buildMap().
#include "apps/DataDirectories.h"
#include "apps/PrepArguments.h"
#include "core/Memory.h"
#include "core/OutputGuard.h"
#include "core/ParallelFor.h"
#include "core/Parse.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/QuadtreeBuilder.h"
#include "quadtree/QuantizedGrid.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/DetailSynthesizer.h"

#include <unistd.h>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace terrain;

/// The synthesizer the viewer will use below the static leaves, with the materials loaded as the viewer
/// loads them (errors name the file and line; warnings go to `warnings`), and its recipe for the map. Null
/// when the chunk size is not 2^k + 1 (buildMap reports it).
Expected<std::unique_ptr<const DetailSynthesizer>> makeSynthesizer(PrepArguments& args,
                                                                   std::vector<std::string>& warnings)
{
    DetailSettings settings = args.detail;
    if (!args.materials.empty()) {
        auto set = loadDetailMaterials(args.materials, warnings);
        TERRAIN_TRY(set);
        settings.materials = std::move(set).value();
    }
    auto recipe = makeDetailRecipe(settings, args.materials);
    TERRAIN_TRY(recipe);
    recipe->roughness = !args.noRoughness;
    args.build.detailRecipe = std::move(recipe).value();
    if (!isValidChunkSize(args.build.chunkSize)) {
        return std::unique_ptr<const DetailSynthesizer>();
    }
    return DetailSynthesizer::create(args.build.chunkSize, std::move(settings));
}

class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : mEnabled(enabled) {}
    void update(double fraction, std::string_view stage)
    {
        if (!mEnabled) {
            return;
        }
        std::lock_guard lock(mMutex);
        constexpr int kWidth = 40;
        int filled = static_cast<int>(fraction * kWidth + 0.5);
        std::fprintf(stderr, "\r[%.*s%*s] %3d%% %-24.*s", filled, "########################################",
                     kWidth - filled, "", static_cast<int>(fraction * 100 + 0.5), static_cast<int>(stage.size()),
                     stage.data());
        std::fflush(stderr);
        mShown = true;
    }
    void finish()
    {
        if (mShown) {
            std::fprintf(stderr, "\r%*s\r", 72, "");
        }
    }

private:
    bool mEnabled;
    bool mShown = false;
    std::mutex mMutex;
};

}  // namespace

int main(int argc, char** argv)
{
    // Over a file size limit (ulimit -f) write() fails with EFBIG once SIGXFSZ is ignored; by default the
    // signal would kill prep with a core dump instead of the error naming the output.
    std::signal(SIGXFSZ, SIG_IGN);
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--help") == 0) {
            std::fputs(prepUsage().c_str(), stdout);
            return 0;
        }
    }
    auto args = parsePrepArguments(std::vector<std::string>(argv + 1, argv + argc), defaultThreadCount(),
                                   programDataDirectory("materials", TERRAIN_MATERIALS_DIR) / "grass.mat");
    if (!args.ok()) {
        std::fprintf(stderr, "prep: %s\n", args.error().message.c_str());
        return 2;
    }
    if (args->inputs.size() > 1 && !args->output) {
        std::fprintf(stderr, "prep: a mosaic of several inputs needs -o FILE.map\n");
        return 2;
    }
    std::filesystem::path output = args->output ? *args->output : args->inputs.front();
    if (!args->output) {
        // A directory of tiles becomes DIR.map beside it.
        output = std::filesystem::path(output.string().substr(0, output.string().find_last_not_of('/') + 1));
        output.replace_extension(".map");
    }
    std::vector<InputFile> inputs = {{"texture (-t)", args->build.texture.value_or(std::filesystem::path())},
                                     {"weight map (-w)", args->build.weights.value_or(std::filesystem::path())}};
    for (const auto& material : args->materials) {
        inputs.push_back({"material", material});
    }
    for (const auto& input : args->inputs) {
        inputs.push_back({"height field", input});
    }
    if (auto refused = refuseInputAsOutput("map", output, inputs); !refused.ok()) {
        std::fprintf(stderr, "prep: %s\n", refused.error().message.c_str());
        return 2;
    }
    std::vector<std::string> warnings = args->warnings;
    auto synthesizer = makeSynthesizer(*args, warnings);
    for (const auto& warning : warnings) {
        std::fprintf(stderr, "prep: warning: %s\n", warning.c_str());
    }
    if (!synthesizer.ok()) {
        std::fprintf(stderr, "prep: %s\n", synthesizer.error().message.c_str());
        return 1;
    }
    if (*synthesizer) {
        args->build.leafDetailError = leafDetailErrorFunction(**synthesizer, !args->noRoughness);
        args->build.detailDisplacementRangeFor = detailDisplacementRangeFunction(**synthesizer);
    }
    configureGdalReading(effectiveMemoryBudget(args->build), args->build.threads);
    auto source = openHeightRows(args->inputs, args->read);
    if (!source.ok()) {
        std::fprintf(stderr, "prep: %s\n", source.error().message.c_str());
        return 1;
    }
    const HeightField& field = (*source)->info();
    for (const auto& note : field.notes) {
        std::fprintf(stderr, "prep: note: %s\n", note.c_str());
    }

    ProgressBar bar(::isatty(STDERR_FILENO) != 0);
    args->build.progress = [&](double fraction, std::string_view stage) { bar.update(fraction, stage); };
    args->build.warn = [&](std::string_view message) {
        bar.finish();
        std::fprintf(stderr, "prep: warning: %.*s\n", static_cast<int>(message.size()), message.data());
    };
    args->build.note = [&](std::string_view message) {
        bar.finish();
        std::fprintf(stderr, "prep: note: %.*s\n", static_cast<int>(message.size()), message.data());
    };
    const std::string description = field.description;
    auto report = buildMap(**source, args->build, output);
    bar.finish();
    if (!report.ok()) {
        std::fprintf(stderr, "prep: %s: %s\n", args->inputs.front().c_str(), report.error().message.c_str());
        return 1;
    }
    const MapHeader& h = report->header;
    const double inputSamples = static_cast<double>(report->inputWidth) * report->inputHeight;
    std::printf("prep: wrote %s\n", output.c_str());
    std::printf("  input     %s: %d x %d samples, spacing %g m\n", description.c_str(), report->inputWidth,
                report->inputHeight, h.sampleSpacing);
    if (!h.crsWkt.empty()) {
        std::printf("            CRS %s, origin %.3f, %.3f m\n", describeCrs(h.crsWkt).c_str(), h.originX, h.originY);
    }
    if (report->imageryCoverage) {
        std::printf("            imagery %s covers %.1f%% of the terrain\n", args->build.texture->c_str(),
                    100.0 * *report->imageryCoverage);
    }
    if (h.noDataFilled > 0) {
        std::printf("            %llu no-data samples filled from their neighbours\n",
                    static_cast<unsigned long long>(h.noDataFilled));
    }
    std::printf("  quadtree  %u levels, %llu nodes of %u x %u samples (grid %llu x %llu), textures %u x %u\n", h.levels,
                static_cast<unsigned long long>(report->nodes), h.chunkSize, h.chunkSize,
                static_cast<unsigned long long>(h.gridSize()), static_cast<unsigned long long>(h.gridSize()),
                h.textureSize, h.textureSize);
    std::printf("  heights   step %g m, %s\n", h.heightStep, describeHeightCoding(h).c_str());
    std::printf("  file      %s: heights %s (%.2f bits per input sample, %.2f per stored sample),\n",
                formatBytes(report->fileBytes).c_str(), formatBytes(report->heightBytes).c_str(),
                8.0 * static_cast<double>(report->heightBytes) / inputSamples,
                8.0 * static_cast<double>(report->heightBytes) / static_cast<double>(report->storedSamples));
    std::printf("            textures %s (%.2f bits per input sample)\n", formatBytes(report->textureBytes).c_str(),
                8.0 * static_cast<double>(report->textureBytes) / inputSamples);
    std::printf(
        "  detail    leaf error max %.3f m, mean %.3f m over %llu leaves (3.4.1, the synthesis model: "
        "synthesis/DetailErrorModel.h)\n",
        static_cast<double>(report->maxLeafDetailError), report->meanLeafDetailError,
        static_cast<unsigned long long>(report->leaves));
    std::printf("            for %s; %.2f s estimating (summed over threads)\n",
                h.detailRecipe ? h.detailRecipe->describe().c_str() : "no recipe", report->leafDetailSeconds);
    std::printf("  time      %.2f s, %.1f million input samples per second (%d threads)\n", report->seconds,
                inputSamples / report->seconds / 1e6, report->threads);
    std::printf("  memory    peak %s, %s (budget %s", formatBytes(peakResidentBytes()).c_str(),
                report->outOfCore ? "out of core" : "in memory", formatBytes(report->memoryBudget).c_str());
    if (report->outOfCore) {
        std::printf("; anonymous memory estimated at %s", formatBytes(report->estimatedBytes).c_str());
    }
    std::printf(")\n");
    return 0;
}
