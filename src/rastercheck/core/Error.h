#pragma once

#include <stdexcept>
#include <string>

namespace rastercheck
{
/** \brief Base of every exception rastercheck throws while loading or setting up. The hot path
    (checking states) never throws; it returns verdicts. */
class Error : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/** \brief A file could not be read or does not say what it must. The message names the file and,
    where known, the element ("link 'panda_link6' collision mesh: ..."). */
class InputError : public Error
{
public:
    InputError(const std::string &file, const std::string &element, const std::string &what)
      : Error(format(file, element, what)), file_(file), element_(element)
    {
    }

    /** \brief The file the error is about (may be empty for in-memory input). */
    const std::string &file() const { return file_; }
    /** \brief The element inside the file ("joint 'j1' limit"); may be empty. */
    const std::string &element() const { return element_; }

private:
    static std::string format(const std::string &file, const std::string &element, const std::string &what)
    {
        std::string message = file.empty() ? std::string("<input>") : file;
        if (!element.empty())
            message += ": " + element;
        return message + ": " + what;
    }

    std::string file_;
    std::string element_;
};

/** \brief A request or configuration that cannot be satisfied (wrong sizes, unknown names, bad
    options). */
class ConfigurationError : public Error
{
public:
    using Error::Error;
};
}  // namespace rastercheck
