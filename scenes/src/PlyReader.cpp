// PLY, ASCII or binary, read into faces (MeshReading.h). Design note: the header is read first
// (readPlyHeader) and says where hapto's values are (plyLayout); the body is then read value by
// value in the header's order (PlyReader knows its place for messages), every element the
// header declares must be there and nothing after them, and only the vertex positions and the
// faces' vertex_indices are kept; other elements and properties are read past.
//
// PLY as in Greg Turk, "The PLY Polygon File Format" (1994; paulbourke.net/dataformats/ply):
// a header `ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`, `comment` and
// `obj_info` lines, `element NAME COUNT` each followed by its `property TYPE NAME` or
// `property list COUNT_TYPE ITEM_TYPE NAME` lines, and `end_header`; then every element's
// instances in header order, each property in order (ASCII: numbers separated by white space,
// binary: packed values of the declared types). Types: char uchar short ushort int uint float
// double, or int8 uint8 int16 uint16 int32 uint32 float32 float64.

#include "MeshReading.h"

#include <bit>
#include <cstring>

namespace hapto::detail {
namespace {

enum class PlyType : std::uint8_t { I8, U8, I16, U16, I32, U32, F32, F64 };

std::optional<PlyType> plyType(std::string_view t) {
    static constexpr std::pair<const char*, PlyType> kNames[] = {
        {"char", PlyType::I8},     {"int8", PlyType::I8},     {"uchar", PlyType::U8},
        {"uint8", PlyType::U8},    {"short", PlyType::I16},   {"int16", PlyType::I16},
        {"ushort", PlyType::U16},  {"uint16", PlyType::U16},  {"int", PlyType::I32},
        {"int32", PlyType::I32},   {"uint", PlyType::U32},    {"uint32", PlyType::U32},
        {"float", PlyType::F32},   {"float32", PlyType::F32}, {"double", PlyType::F64},
        {"float64", PlyType::F64},
    };
    for (const auto& [n, type] : kNames) {
        if (t == n) {
            return type;
        }
    }
    return std::nullopt;
}

std::size_t plySize(PlyType t) {
    switch (t) {
    case PlyType::I8:
    case PlyType::U8:
        return 1;
    case PlyType::I16:
    case PlyType::U16:
        return 2;
    case PlyType::I32:
    case PlyType::U32:
    case PlyType::F32:
        return 4;
    case PlyType::F64:
        return 8;
    }
    return 0;
}

bool plyIsFloat(PlyType t) {
    return t == PlyType::F32 || t == PlyType::F64;
}

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType countType = PlyType::U8;
    PlyType type = PlyType::F32;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { Ascii, Little, Big };

/// Reads the body's values one by one, ASCII or binary, knowing where it is for messages.
class PlyReader {
public:
    PlyReader(std::string_view bytes, std::size_t bodyStart, std::size_t bodyLine, PlyFormat f,
              const std::string& name)
        : mBytes(bytes), mAt(bodyStart), mLine(bodyLine), mFormat(f), mName(name) {}

    /// Where a value starts: its byte and line.
    struct Mark {
        std::size_t at, line;
    };
    /// Where the next value starts (cheap: no text is made until a message needs it).
    Mark mark() {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
        }
        return {mAt, mLine};
    }
    /// Moves to the next element: in ASCII, one element is one line (assimp's reader is
    /// line-based, and misreads, then aborts on, an element split over lines).
    void beginElement() {
        if (mFormat == PlyFormat::Ascii) {
            skipSpace();
        }
    }
    /// True when an ASCII element's line has ended (next() returned nullopt before the end of
    /// the file).
    bool atLineEnd() const {
        return mFormat == PlyFormat::Ascii && mAt < mBytes.size() && mBytes[mAt] == '\n';
    }
    /// Refuses values left on an ASCII element's line. `what` names the element.
    template <class What> void endElement(const What& what) {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
            if (mAt < mBytes.size() && mBytes[mAt] != '\n') {
                fail(atLine(mName, mLine) + "more values on the line of " + what() +
                     " than its properties (an ASCII PLY element is one line)");
            }
        }
    }
    /// A mark for messages: "NAME:LINE: " (ASCII) or "NAME: byte N: " (binary).
    std::string place(Mark m) const {
        return mFormat == PlyFormat::Ascii ? atLine(mName, m.line) : atByte(mName, m.at);
    }
    /// The next value; nullopt at the end of the file (or, in ASCII, of the element's line).
    /// Throws for text that is not a number.
    std::optional<double> next(PlyType t) {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
            if (mAt >= mBytes.size() || mBytes[mAt] == '\n') {
                return std::nullopt;
            }
            const std::size_t start = mAt;
            while (mAt < mBytes.size() && !isSpace(mBytes[mAt]) && mBytes[mAt] != '\n') {
                ++mAt;
            }
            const std::string_view token = mBytes.substr(start, mAt - start);
            const auto v = plyIsFloat(t) ? parseNumber(token) : parseIntegerAsDouble(token);
            if (!v) {
                fail(atLine(mName, mLine) + quoted(token) + " is not " +
                     (plyIsFloat(t) ? "a number" : "a whole number"));
            }
            return v;
        }
        const std::size_t n = plySize(t);
        if (mBytes.size() - mAt < n) {
            return std::nullopt;
        }
        unsigned char raw[8];
        std::memcpy(raw, mBytes.data() + mAt, n);
        if ((mFormat == PlyFormat::Big) != (std::endian::native == std::endian::big)) {
            for (std::size_t i = 0; i < n / 2; ++i) {
                std::swap(raw[i], raw[n - 1 - i]);
            }
        }
        mAt += n;
        switch (t) {
        case PlyType::I8:
            return static_cast<double>(std::bit_cast<std::int8_t>(raw[0]));
        case PlyType::U8:
            return static_cast<double>(raw[0]);
        case PlyType::I16:
            return static_cast<double>(load<std::int16_t>(raw));
        case PlyType::U16:
            return static_cast<double>(load<std::uint16_t>(raw));
        case PlyType::I32:
            return static_cast<double>(load<std::int32_t>(raw));
        case PlyType::U32:
            return static_cast<double>(load<std::uint32_t>(raw));
        case PlyType::F32:
            return static_cast<double>(load<float>(raw));
        case PlyType::F64:
            return load<double>(raw);
        }
        return std::nullopt;
    }
    /// True when nothing but (ASCII) white space is left.
    bool atEnd() {
        if (mFormat == PlyFormat::Ascii) {
            skipSpace();
        }
        return mAt >= mBytes.size();
    }

private:
    template <class T> static T load(const unsigned char* raw) {
        T v;
        std::memcpy(&v, raw, sizeof v);
        return v;
    }
    static std::optional<double> parseIntegerAsDouble(std::string_view t) {
        const auto i = parseInteger(t);
        return i ? std::optional<double>(static_cast<double>(*i)) : std::nullopt;
    }
    void skipBlanks() {
        while (mAt < mBytes.size() && isSpace(mBytes[mAt])) {
            ++mAt;
        }
    }
    void skipSpace() {
        while (mAt < mBytes.size() && (isSpace(mBytes[mAt]) || mBytes[mAt] == '\n')) {
            mLine += mBytes[mAt] == '\n';
            ++mAt;
        }
    }

    std::string_view mBytes;
    std::size_t mAt;
    std::size_t mLine;
    PlyFormat mFormat;
    const std::string& mName;
};

/// A PLY header as read: its elements in order, its format, and where its body starts.
struct PlyHeader {
    std::vector<PlyElement> elements;
    PlyFormat format = PlyFormat::Ascii;
    std::size_t bodyStart = 0; ///< The byte after end_header's newline.
    std::size_t bodyLine = 0;  ///< The line the body starts on.
};

/// Reads the header: lines up to end_header, each one the specification's.
PlyHeader readPlyHeader(std::string_view bytes, const std::string& name) {
    std::vector<PlyElement> elements;
    std::optional<PlyFormat> format;
    std::vector<std::string_view> tok;
    std::size_t at = 0;
    std::size_t lineNo = 0;
    bool ended = false;
    while (!ended) {
        if (at >= bytes.size()) {
            fail(name + ": the PLY header has no end_header line");
        }
        std::size_t end = bytes.find('\n', at);
        if (end == std::string_view::npos) {
            end = bytes.size();
        }
        const std::string_view line = bytes.substr(at, end - at);
        at = std::min(end + 1, bytes.size()); // the body starts after end_header's newline
        ++lineNo;
        const auto place = [&] { return atLine(name, lineNo); };
        tokens(line, tok);
        if (lineNo == 1) {
            if (tok.size() != 1 || tok[0] != "ply") {
                fail(place() + "not a PLY file (the first line must be 'ply')");
            }
            continue;
        }
        if (tok.empty()) {
            fail(place() + "a blank line in the PLY header (the format has none, and other readers "
                           "(assimp) misread some: remove it)");
        }
        if (tok[0] == "comment" || tok[0] == "obj_info") {
            continue;
        }
        if (tok[0] == "format") {
            if (tok.size() != 3 || tok[2] != "1.0") {
                fail(place() +
                     "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            }
            if (tok[1] == "ascii") {
                format = PlyFormat::Ascii;
            } else if (tok[1] == "binary_little_endian") {
                format = PlyFormat::Little;
            } else if (tok[1] == "binary_big_endian") {
                format = PlyFormat::Big;
            } else {
                fail(place() + "unknown PLY format " + quoted(tok[1]));
            }
        } else if (tok[0] == "element") {
            const auto count = tok.size() == 3 ? parseInteger(tok[2]) : std::nullopt;
            if (!count || *count < 0) {
                fail(place() + "expected 'element NAME COUNT'");
            }
            elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(*count), {}});
        } else if (tok[0] == "property") {
            if (elements.empty()) {
                fail(place() + "a property before any element");
            }
            PlyProperty p;
            const bool list = tok.size() == 5 && tok[1] == "list";
            if (!list && tok.size() != 3) {
                fail(place() + "expected 'property TYPE NAME' or 'property list COUNT_TYPE "
                               "ITEM_TYPE NAME'");
            }
            const auto count = list ? plyType(tok[2]) : std::optional<PlyType>(PlyType::U8);
            const auto type = plyType(tok[list ? 3 : 1]);
            if (!count || !type || (list && plyIsFloat(*count))) {
                fail(place() + "unknown property type in " + quoted(line));
            }
            elements.back().properties.push_back(
                {std::string(tok[list ? 4 : 2]), list, *count, *type});
        } else if (tok[0] == "end_header") {
            if (tok.size() != 1) {
                fail(place() + "expected 'end_header' alone on its line (the body starts after "
                               "its newline)");
            }
            ended = true;
        } else {
            fail(place() + "unknown PLY header line " + quoted(line));
        }
    }
    if (!format) {
        fail(name + ": the PLY header has no format line");
    }
    return {std::move(elements), *format, at, lineNo + 1};
}

/// Where hapto's values are in a PLY file's elements: the vertex element and its x, y, z
/// properties, the face element and its vertex_indices list.
struct PlyLayout {
    const PlyElement* vertex = nullptr;
    const PlyElement* face = nullptr;
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
};

/// Finds the elements and properties hapto needs, and checks their counts against the limits.
PlyLayout plyLayout(const std::vector<PlyElement>& elements, const std::string& name) {
    const PlyElement* vertex = nullptr;
    const PlyElement* face = nullptr;
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    for (const PlyElement& e : elements) {
        vertex = e.name == "vertex" ? &e : vertex;
        face = e.name == "face" ? &e : face;
    }
    if (!vertex) {
        fail(name + ": the PLY header declares no 'vertex' element");
    }
    if (!face) {
        fail(name + ": no triangles (the PLY header declares no 'face' element)");
    }
    for (std::size_t i = 0; i < vertex->properties.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            if (vertex->properties[i].name == kAxis[c] && !vertex->properties[i].list) {
                xyz[c] = static_cast<int>(i);
            }
        }
    }
    for (int c = 0; c < 3; ++c) {
        if (xyz[c] < 0) {
            fail(name + ": the PLY vertex element has no property " + kAxis[c]);
        }
    }
    for (std::size_t i = 0; i < face->properties.size(); ++i) {
        const PlyProperty& p = face->properties[i];
        if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
            indices = static_cast<int>(i);
            if (plyIsFloat(p.type)) {
                fail(name + ": the PLY face list " + p.name + " must hold whole numbers");
            }
        }
    }
    if (indices < 0) {
        fail(name + ": the PLY face element has no 'vertex_indices' list");
    }
    if (vertex->count > TriangleMesh::kMaxVertices) {
        fail(name + ": " + std::to_string(vertex->count) + " vertices; a mesh may have at most " +
             std::to_string(TriangleMesh::kMaxVertices));
    }
    checkTriangleLimit(face->count, name);
    if (face->count == 0) {
        fail(name + ": no triangles (the PLY header declares 0 faces)");
    }
    return {vertex, face, {xyz[0], xyz[1], xyz[2]}, indices};
}

/// Reads a PLY body element by element, keeping the vertex positions and the faces.
class PlyBodyWalk {
public:
    PlyBodyWalk(std::string_view bytes, const PlyHeader& header, const PlyLayout& layout,
                const std::string& name, double scale)
        : mReader(bytes, header.bodyStart, header.bodyLine, header.format, name), mLayout(layout),
          mName(name), mScale(scale) {
        mModel.vertices.reserve(static_cast<std::size_t>(layout.vertex->count));
    }

    /// Reads every element of `elements` (the header's, in order) and refuses anything after.
    ModelFaces read(const std::vector<PlyElement>& elements) {
        for (const PlyElement& e : elements) {
            for (std::uint64_t i = 0; i < e.count; ++i) {
                const auto what = [&] { return e.name + " element " + std::to_string(i); };
                mReader.beginElement();
                if (&e == mLayout.vertex) {
                    mModel.vertices.emplace_back();
                }
                for (std::size_t k = 0; k < e.properties.size(); ++k) {
                    property(e, k, what);
                }
                mReader.endElement(what);
            }
        }
        if (!mReader.atEnd()) {
            fail(mReader.place(mReader.mark()) +
                 "data after the last element the header declares (" +
                 std::to_string(mLayout.face->count) + " faces, " +
                 std::to_string(mLayout.vertex->count) + " vertices)");
        }
        return std::move(mModel);
    }

private:
    /// Reads property `k` of an element `e`; `what` names the element for messages.
    template <class What> void property(const PlyElement& e, std::size_t k, const What& what) {
        const PlyProperty& p = e.properties[k];
        mMark = mReader.mark();
        const auto value = mReader.next(p.list ? p.countType : p.type);
        if (!value) {
            truncated(e, what);
        }
        if (!p.list) {
            const int axis = &e == mLayout.vertex ? axisOf(k) : -1;
            if (axis >= 0) {
                if (const std::string problem = coordinateProblem(*value, mScale);
                    !problem.empty()) {
                    fail(mReader.place(mMark) + what() + ": " + p.name + " " + problem);
                }
                mModel.vertices.back()[axis] = static_cast<float>(*value);
            }
            return;
        }
        const double n = *value;
        if (n < 0) {
            fail(mReader.place(mMark) + what() + ": a negative list length");
        }
        const bool isIndices = &e == mLayout.face && static_cast<int>(k) == mLayout.indices;
        if (isIndices) {
            faceSize(n, what);
        }
        for (std::uint64_t j = 0; j < static_cast<std::uint64_t>(n); ++j) {
            mMark = mReader.mark();
            const auto item = mReader.next(p.type);
            if (!item) {
                truncated(e, what);
            }
            if (isIndices) {
                corner(*item, what);
            }
        }
        if (isIndices) {
            mTriangles += static_cast<std::uint64_t>(n) - 2;
            checkTriangleLimit(mTriangles, mName);
        }
    }

    /// Which of x, y, z the vertex property `k` is (0, 1, 2), or -1.
    int axisOf(std::size_t k) const {
        for (int c = 0; c < 3; ++c) {
            if (static_cast<int>(k) == mLayout.xyz[c]) {
                return c;
            }
        }
        return -1;
    }

    /// A face's vertex count `n`: 3 to kMaxFaceVertices.
    template <class What> void faceSize(double n, const What& what) {
        if (n < 3) {
            fail(mReader.place(mMark) + what() + ": a face needs at least 3 vertices, got " +
                 std::to_string(static_cast<long long>(n)));
        }
        checkFaceSize(static_cast<std::uint64_t>(n), mReader.place(mMark) + what() + ": ", "face");
        mModel.faceSizes.push_back(static_cast<std::uint16_t>(n));
    }

    /// A face's vertex index, refused unless it names a vertex.
    template <class What> void corner(double index, const What& what) {
        const std::uint64_t count = mLayout.vertex->count;
        if (!(index >= 0 && index < static_cast<double>(count))) {
            fail(mReader.place(mMark) + what() + ": vertex index " +
                 std::to_string(static_cast<long long>(index)) + " is out of range (the file has " +
                 std::to_string(count) + " vertices)");
        }
        mModel.corners.push_back(static_cast<std::uint32_t>(index));
    }

    /// Refuses an element cut short by the end of its line (ASCII) or of the file.
    template <class What> [[noreturn]] void truncated(const PlyElement& e, const What& what) {
        if (mReader.atLineEnd()) {
            fail(mReader.place(mMark) + "the line ends inside " + what() +
                 " (an ASCII PLY element is one line, with a value for each of its "
                 "properties)");
        }
        fail(mReader.place(mMark) + "the file ends inside " + what() +
             ", but the header declares " + std::to_string(e.count) + " " + e.name + " elements");
    }

    PlyReader mReader;
    const PlyLayout& mLayout;
    const std::string& mName;
    double mScale;
    PlyReader::Mark mMark{0, 0};
    std::uint64_t mTriangles = 0;
    ModelFaces mModel;
};

} // namespace

ModelFaces readPly(std::string_view bytes, const std::string& name, double scale) {
    const PlyHeader header = readPlyHeader(bytes, name);
    const PlyLayout layout = plyLayout(header.elements, name);
    return PlyBodyWalk(bytes, header, layout, name, scale).read(header.elements);
}

} // namespace hapto::detail
