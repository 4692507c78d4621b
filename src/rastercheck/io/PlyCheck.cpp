#include "rastercheck/io/PlyCheck.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <vector>

#include "rastercheck/core/Error.h"

// The rules below mirror what assimp 5.2.5 (Debian 12) does, measured on crafted files where its
// source left doubt; tests/data/fuzz-regressions/mesh/ holds the inputs that broke it.

namespace rastercheck::detail
{
namespace
{
bool lineEnd(char c)
{
    return c == '\n' || c == '\r' || c == '\0' || c == '\f';
}

// The lines of a file as assimp's IOStreamBuffer::getNextLine returns them: a line ends at \n, \r,
// \0 or \f, and where a line would start on one of those, everything up to and including the next
// \n is skipped (a blank line vanishes, and so does the "end_header" of "\r\rend_header").
class Lines
{
public:
    Lines(const char *data, std::size_t size) : data_(data), size_(size) {}

    bool next(std::string &line)
    {
        if (position_ >= size_)
            return false;
        if (lineEnd(data_[position_]))
        {
            while (position_ < size_ && data_[position_] != '\n')
                ++position_;
            if (++position_ >= size_)
                return false;
        }
        const std::size_t start = position_;
        while (position_ < size_ && !lineEnd(data_[position_]))
            ++position_;
        line.assign(data_ + start, position_ - start);
        ++position_;  // the character that ended the line
        ++number_;
        return true;
    }

    // Where the binary body starts after the line just read: past the character that ended it and
    // past one more \n (measured: "end_header\r\n" and "end_header\n\n" both start after the \n).
    std::size_t binaryStart() const
    {
        std::size_t start = std::min(position_, size_);
        if (start < size_ && data_[start] == '\n')
            ++start;
        return start;
    }

    std::size_t position() const { return std::min(position_, size_); }
    int number() const { return number_; }

private:
    const char *data_;
    std::size_t size_;
    std::size_t position_ = 0;
    int number_ = 0;
};

// Tokens as assimp separates them (spaces and tabs).
std::vector<std::string> tokens(const std::string &line)
{
    std::vector<std::string> out;
    std::size_t i = 0;
    while (i < line.size())
    {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t')
            ++i;
        if (i > start)
            out.push_back(line.substr(start, i - start));
    }
    return out;
}

bool wholeNumber(const std::string &token, std::size_t maxDigits)
{
    return !token.empty() && token.size() <= maxDigits &&
           std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; });
}

struct Type
{
    std::size_t size = 0;
    bool integer = false;
    bool isSigned = false;
};

bool parseType(const std::string &name, Type &type)
{
    static const std::pair<const char *, Type> types[] = {
        {"char", {1, true, true}},     {"int8", {1, true, true}},      {"uchar", {1, true, false}},
        {"uint8", {1, true, false}},   {"short", {2, true, true}},     {"int16", {2, true, true}},
        {"ushort", {2, true, false}},  {"uint16", {2, true, false}},   {"int", {4, true, true}},
        {"int32", {4, true, true}},    {"uint", {4, true, false}},     {"uint32", {4, true, false}},
        {"float", {4, false, false}},  {"float32", {4, false, false}}, {"double", {8, false, false}},
        {"float64", {8, false, false}}};
    for (const auto &[typeName, value] : types)
        if (name == typeName)
        {
            type = value;
            return true;
        }
    return false;
}

struct Property
{
    bool list = false;
    Type count;  // lists only
    Type value;
};

struct Element
{
    std::string name;
    unsigned long long count = 0;
    std::vector<Property> properties;
};

long long readInteger(const unsigned char *bytes, const Type &type, bool bigEndian)
{
    std::uint32_t raw = 0;
    for (std::size_t i = 0; i < type.size; ++i)
        raw |= static_cast<std::uint32_t>(bytes[bigEndian ? type.size - 1 - i : i]) << (8 * i);
    if (!type.isSigned)
        return raw;
    const std::uint32_t sign = std::uint32_t(1) << (8 * type.size - 1);
    return static_cast<long long>(raw ^ sign) - static_cast<long long>(sign);  // two's complement
}
}  // namespace

bool looksLikePly(const char *data, std::size_t size)
{
    std::size_t i = 0;
    while (i < size && std::isspace(static_cast<unsigned char>(data[i])))
        ++i;
    return size - i >= 3 && std::tolower(static_cast<unsigned char>(data[i])) == 'p' &&
           std::tolower(static_cast<unsigned char>(data[i + 1])) == 'l' &&
           std::tolower(static_cast<unsigned char>(data[i + 2])) == 'y';
}

void checkPly(const char *data, std::size_t size, const std::string &name)
{
    Lines lines(data, size);
    std::string line;
    auto headerError = [&](const std::string &what)
    { return InputError(name, "PLY header line " + std::to_string(lines.number()), what); };

    std::vector<std::string> t;
    if (!lines.next(line) || (t = tokens(line)).size() != 1 || !looksLikePly(t[0].data(), t[0].size()) ||
        t[0].size() != 3)
        throw headerError("expected 'ply'");
    if (!lines.next(line) || (t = tokens(line)).size() != 3 || t[0] != "format" ||
        (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian"))
        throw headerError("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
    const bool ascii = t[1] == "ascii", bigEndian = t[1] == "binary_big_endian";

    std::vector<Element> elements;
    bool ended = false;
    while (!ended && lines.next(line))
    {
        t = tokens(line);
        if (t.size() == 1 && t[0] == "end_header")
            ended = true;
        else if (!t.empty() && (t[0] == "comment" || t[0] == "obj_info"))
        {
            // assimp takes a comment after an element for the end of its properties (measured).
            if (!elements.empty())
                throw headerError("comments are read only before the first element");
        }
        else if (!t.empty() && t[0] == "element")
        {
            // assimp reads the count only after a name it knows; after another it reads 0 instances
            // and so the body differently.
            static const char *const known[] = {"vertex", "face", "tristrips", "edge", "material"};
            if (t.size() != 3 || !wholeNumber(t[2], 19))
                throw headerError("expected 'element NAME COUNT'");
            if (std::none_of(std::begin(known), std::end(known), [&](const char *k) { return t[1] == k; }))
                throw headerError("element '" + t[1] +
                                  "': rastercheck reads vertex, face, tristrips, edge and material");
            elements.push_back({t[1], std::stoull(t[2]), {}});
        }
        else if (!t.empty() && t[0] == "property")
        {
            Property property;
            if (elements.empty())
                throw headerError("property before the first element");
            if (t.size() == 5 && t[1] == "list" && parseType(t[2], property.count) && property.count.integer &&
                parseType(t[3], property.value))
                property.list = true;
            else if (t.size() != 3 || !parseType(t[1], property.value))
                throw headerError("expected 'property TYPE NAME' or 'property list INTEGER_TYPE TYPE NAME'");
            elements.back().properties.push_back(property);
        }
        else
            throw headerError("not a PLY header line (element, property, comment, obj_info or end_header)");
    }
    if (!ended)
        throw InputError(name, "PLY header", "no end_header line");

    // Element counts first, so the walk below is short: a body must have room for what it declares.
    const std::size_t bodyStart = ascii ? lines.position() : lines.binaryStart();
    const unsigned long long available = size - bodyStart + 1;
    unsigned long long needed = 0;
    for (const Element &element : elements)
    {
        std::size_t each = 0;  // bytes an instance takes at least: a value and a blank (ASCII), its size
        for (const Property &property : element.properties)
            each += ascii ? 2 : (property.list ? property.count.size : property.value.size);
        each = std::max<std::size_t>(each, ascii ? 2 : 1);  // an ASCII line, or assimp's allocation
        if (element.count > available / each || needed + element.count * each > available)
            throw InputError(name, "PLY element '" + element.name + "'",
                             "declares " + std::to_string(element.count) + " instances, more than the " +
                                 std::to_string(size - bodyStart) + " bytes after the header can hold");
        needed += element.count * each;
    }

    // Every instance and every list as assimp will read them.
    std::size_t at = bodyStart;
    for (const Element &element : elements)
        for (unsigned long long k = 0; k < element.count; ++k)
        {
            const std::string where = "PLY element '" + element.name + "' #" + std::to_string(k);
            if (ascii)
            {
                if (!lines.next(line))
                    throw InputError(name, where, "the file ends before this instance");
                t = tokens(line);
                std::size_t next = 0;
                for (const Property &property : element.properties)
                {
                    if (next >= t.size())
                        throw InputError(name, where, "fewer values than properties");
                    if (!property.list)
                    {
                        ++next;
                        continue;
                    }
                    if (!wholeNumber(t[next], 19))
                        throw InputError(name, where, "list length '" + t[next] + "' is not a whole number");
                    const unsigned long long length = std::stoull(t[next++]);
                    if (length > t.size() - next)
                        throw InputError(name, where,
                                         "list of " + std::to_string(length) + " values has " +
                                             std::to_string(t.size() - next) + " on its line");
                    next += static_cast<std::size_t>(length);
                }
                continue;
            }
            for (const Property &property : element.properties)
            {
                const std::size_t head = property.list ? property.count.size : property.value.size;
                if (size - at < head)
                    throw InputError(name, where, "the file ends inside this instance");
                if (!property.list)
                {
                    at += head;
                    continue;
                }
                const long long length =
                    readInteger(reinterpret_cast<const unsigned char *>(data + at), property.count, bigEndian);
                at += head;
                if (length < 0 || static_cast<unsigned long long>(length) > (size - at) / property.value.size)
                    throw InputError(name, where,
                                     "list of " + std::to_string(length) + " values runs past the end of the file");
                at += static_cast<std::size_t>(length) * property.value.size;
            }
        }
}
}  // namespace rastercheck::detail
