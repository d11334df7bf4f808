#include "core/OutputGuard.h"

namespace terrain {

bool isSameFile(const std::filesystem::path& a, const std::filesystem::path& b)
{
    std::error_code ec;
    if (std::filesystem::equivalent(a, b, ec) && !ec) {
        return true;  // same inode: the same path, a symbolic link to it, or a hard link
    }
    // A path that does not exist yet (or cannot be checked) is compared by its resolved name.
    const auto ra = std::filesystem::weakly_canonical(a, ec);
    if (ec) {
        return false;
    }
    const auto rb = std::filesystem::weakly_canonical(b, ec);
    return !ec && ra == rb;
}

Status refuseInputAsOutput(const std::string& outputRole, const std::filesystem::path& output,
                           std::span<const InputFile> inputs)
{
    for (const InputFile& input : inputs) {
        if (!input.path.empty() && isSameFile(output, input.path)) {
            const bool sameName = output.lexically_normal() == input.path.lexically_normal();
            const std::string which = sameName ? std::string() : input.path.string();
            return makeError("refusing to write the ", outputRole, " to ", output.string(), ": it is the ", input.role,
                             sameName ? "" : " ", which, sameName ? " itself" : " (the same file)",
                             "; nothing was written, choose another output path");
        }
    }
    return {};
}

}  // namespace terrain
