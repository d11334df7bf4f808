#include "apps/DataDirectories.h"

#include <system_error>

namespace terrain {

std::filesystem::path programDataDirectory(std::string_view kind, const std::filesystem::path& sourceTree)
{
    std::error_code error;
    const std::filesystem::path executable = std::filesystem::read_symlink("/proc/self/exe", error);
    if (!error && executable.parent_path().filename() == TERRAIN_INSTALL_BIN_DIR) {
        const std::filesystem::path installed =
            executable.parent_path().parent_path() / TERRAIN_INSTALL_DATA_DIR / std::filesystem::path(kind);
        if (std::filesystem::is_directory(installed, error)) {
            return installed;
        }
    }
    return sourceTree;
}

}  // namespace terrain
