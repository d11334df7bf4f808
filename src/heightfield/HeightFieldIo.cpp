// Choosing a height field reader by extension (paper 4.1), and the helpers every format shares.
// The formats live in PngHeightField.cpp, BtHeightField.cpp, TerHeightField.cpp and RawHeightField.cpp.
#include "heightfield/HeightFieldIo.h"

#include "core/Memory.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIoSupport.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>

namespace terrain {

namespace detail {

Expected<InputFile> InputFile::open(const std::filesystem::path& path)
{
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        return makeError(path.string(), ": cannot open: is a directory");
    }
    InputFile file;
    file.mPath = path;
    file.mFile.reset(std::fopen(path.c_str(), "rb"));
    if (!file.mFile) {
        return makeError(path.string(), ": cannot open: ", std::strerror(errno));
    }
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) {
        return makeError(path.string(), ": cannot read its size: ", ec.message());
    }
    file.mSize = size;
    return file;
}

bool InputFile::readAt(std::uint64_t offset, void* data, std::size_t size)
{
    if (size == 0) {
        return true;
    }
    if (offset > mSize || size > mSize - offset) {
        return false;
    }
    if (::fseeko(mFile.get(), static_cast<off_t>(offset), SEEK_SET) != 0) {
        return false;
    }
    return std::fread(data, 1, size, mFile.get()) == size;
}

Status checkSampleMemory(const std::filesystem::path& path, std::uint64_t width, std::uint64_t height,
                         std::uint64_t extraBytes)
{
    // Both come from int fields, so width * height * 4 stays below 2^64.
    const std::uint64_t bytes = width * height * sizeof(float) + extraBytes;
    std::ostringstream what;
    what << path.string() << ": a " << width << "x" << height << " height field";
    return checkAllocation(bytes, what.str());
}

void allocateSamples(HeightField& field)
{
    field.samples.assign(static_cast<std::size_t>(field.width) * static_cast<std::size_t>(field.height), 0.0f);
}

void applyNoData(HeightField& field, const HeightFieldReadOptions& options)
{
    if (!options.noData) {
        return;
    }
    const double noData = *options.noData;
    for (float& sample : field.samples) {
        if (isNoDataValue(sample, noData)) {
            sample = std::nanf("");
        }
    }
}

Status checkFieldShape(const std::filesystem::path& path, const HeightField& field)
{
    if (field.width < 1 || field.height < 1 ||
        field.samples.size() != static_cast<std::size_t>(field.width) * static_cast<std::size_t>(field.height)) {
        return makeError(path.string(), ": cannot write a ", field.width, "x", field.height, " height field with ",
                         field.samples.size(), " samples (need width, height >= 1 and width * height samples)");
    }
    return {};
}

Status checkNoNaN(const std::filesystem::path& path, const HeightField& field, std::string_view format)
{
    for (int j = 0; j < field.height; ++j) {
        for (int i = 0; i < field.width; ++i) {
            if (std::isnan(field.at(i, j))) {
                return makeError(path.string(), ": sample (", i, ", ", j, ") is no-data (NaN) but ", format,
                                 " has no no-data value");
            }
        }
    }
    return {};
}

std::string formatNumber(double value)
{
    std::ostringstream s;
    s << value;
    return s.str();
}

std::string printableBytes(const std::uint8_t* bytes, std::size_t size)
{
    std::string text;
    for (std::size_t k = 0; k < size; ++k) {
        const unsigned char c = bytes[k];
        if (std::isprint(c) && c != '\\') {
            text += static_cast<char>(c);
        } else {
            static constexpr char kHex[] = "0123456789abcdef";
            text += "\\x";
            text += kHex[c >> 4];
            text += kHex[c & 15];
        }
    }
    return text;
}

}  // namespace detail

namespace {
bool hasOwnReader(const std::filesystem::path& path)
{
    std::string extension = path.extension().string();
    for (char& c : extension) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return extension == ".png" || extension == ".bt" || extension == ".ter" || extension == ".raw" ||
           extension == ".r16" || extension == ".bin";
}
}  // namespace

Expected<std::unique_ptr<HeightRows>> openHeightRows(std::span<const std::filesystem::path> paths,
                                                     const HeightFieldReadOptions& options)
{
    if (paths.size() == 1 && hasOwnReader(paths.front())) {
        auto field = readHeightField(paths.front(), options);
        TERRAIN_TRY(field);
        return std::unique_ptr<HeightRows>(std::make_unique<FieldRows>(std::move(field.value())));
    }
    auto raster = ElevationRaster::open(paths, {options.noData, options.targetSrs});
    TERRAIN_TRY(raster);
    return std::unique_ptr<HeightRows>(std::make_unique<RasterRows>(std::move(raster.value())));
}

Expected<HeightField> readHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options)
{
    std::string extension = path.extension().string();
    for (char& c : extension) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    if (extension == ".png") {
        return readPngHeightField(path, options);
    }
    if (extension == ".bt") {
        return readBtHeightField(path, options);
    }
    if (extension == ".ter") {
        return readTerHeightField(path, options);
    }
    if (extension == ".raw" || extension == ".r16" || extension == ".bin") {
        return readRawHeightField(path, options);
    }
    // Everything else (GeoTIFF, .hgt, .asc, VRT, a directory of tiles, ...) goes through GDAL.
    return readGdalHeightField(std::span(&path, 1), {options.noData, options.targetSrs});
}

Expected<HeightField> readHeightFields(std::span<const std::filesystem::path> paths,
                                       const HeightFieldReadOptions& options)
{
    if (paths.size() == 1) {
        return readHeightField(paths.front(), options);
    }
    return readGdalHeightField(paths, {options.noData, options.targetSrs});
}

}  // namespace terrain
