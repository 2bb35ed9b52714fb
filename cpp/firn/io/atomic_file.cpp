#include "firn/io/atomic_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "firn/util/error.h"

namespace firn {

void writeFileAtomically(const std::string &path, const std::function<void(std::ostream &)> &write) {
    const std::filesystem::path target(path);
    const std::filesystem::path temp = target.string() + ".tmp" + std::to_string(::getpid());
    try {
        if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
        std::ofstream stream;
        stream.exceptions(std::ios_base::failbit | std::ios_base::badbit);
        errno = 0;
        try {
            stream.open(temp, std::ios_base::out | std::ios_base::binary | std::ios_base::trunc);
            write(stream);
            stream.close();
        } catch (const std::ios_base::failure &) {
            // The stream's own message says nothing; the failed system call's errno does (ENOSPC, EROFS...).
            throw std::runtime_error(errno != 0 ? std::strerror(errno) : "write failed");
        }
        std::filesystem::rename(temp, target);
    } catch (const Cancelled &) {  // the writer was cancelled: `path` stays as it was, and the cancel is no error
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw;
    } catch (const std::exception &e) {
        std::error_code ignored;
        std::filesystem::remove(temp, ignored);
        throw WriteError("cannot write " + path + ": " + e.what());
    }
}

}  // namespace firn
