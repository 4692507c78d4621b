#pragma once

#include <string>
#include <sys/stat.h>

/** \file
    Path helpers the loaders, the command line and the Python module share (POSIX paths). */

namespace rastercheck
{
/** \brief Whether \a path names a regular file (following links). */
inline bool isFile(const std::string &path)
{
    struct stat info;
    return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

/** \brief The folder part of \a path: "." when it has none, "/" for a file at the root. */
inline std::string folderOf(const std::string &path)
{
    const std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

/** \brief The last component of \a path. */
inline std::string nameOf(const std::string &path)
{
    const std::size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

/** \brief The last component of \a path without its last extension ("a/b.tar.gz" -> "b.tar"). */
inline std::string stemOf(const std::string &path)
{
    const std::string name = nameOf(path);
    const std::size_t dot = name.find_last_of('.');
    return dot == std::string::npos ? name : name.substr(0, dot);
}

/** \brief The last extension of \a path's last component, without the dot, as written ("" when
    it has none). */
inline std::string extensionOf(const std::string &path)
{
    const std::size_t dot = path.find_last_of('.'), slash = path.find_last_of('/');
    return dot == std::string::npos || (slash != std::string::npos && dot < slash) ? "" : path.substr(dot + 1);
}
}  // namespace rastercheck
