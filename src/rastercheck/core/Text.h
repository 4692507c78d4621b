#pragma once

#include <string>

/** \file
    Text helpers the loaders, the planners' registry, the command line and the viewer share. */

namespace rastercheck
{
/** \brief \a text without leading and trailing spaces, tabs and line ends. */
inline std::string trim(const std::string &text)
{
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos)
        return "";
    return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

/** \brief \a text with ASCII letters in lower case (as std::tolower in the C locale): file
    extensions, names matched without case, HTTP header names and values. */
inline std::string lowerCase(std::string text)
{
    for (char &c : text)
        if (c >= 'A' && c <= 'Z')
            c = static_cast<char>(c - 'A' + 'a');
    return text;
}
}  // namespace rastercheck
