// Wavefront OBJ read into faces (MeshReading.h), in one pass after a count of its vertices.
// Design note: the reader follows the specification (cited below) and refuses, with the line,
// everything it does not read as written; it also refuses what assimp 5.2.5, which hapto read
// models with before, read otherwise than the specification (an indented statement, a word
// beginning with f, l, p, vt or vn, a vertical tab...), so every file hapto accepted then and
// no file it refused loads, to the same mesh. Positions are kept as 32-bit floats, as then.
//
// Wavefront OBJ, as in "Object Files (.obj)", Appendix B1 of the Advanced Visualizer manual
// (Wavefront Technologies): `v x y z [w]` (assimp also read `v x y z r g b`), `vt`, `vn`,
// `f v1[/vt1][/vn1] v2... ` with 1-based indices or negative ones counting back from the last
// vertex defined so far; a line ending with '\' continues on the next one; '#' starts a comment.

#include "MeshReading.h"

#include "hapto/scenes/TriangleMesh.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

namespace hapto::detail {
namespace {

struct ObjCounts {
    std::int64_t v = 0, vt = 0, vn = 0;
};

/// Calls f(firstLine, logicalLine) per logical line (continuations joined, comment cut).
template <class F> void forEachObjLine(std::string_view text, F&& f) {
    std::string joined;
    std::size_t joinedFrom = 0;
    forEachLine(text, [&](std::size_t line, std::string_view l) {
        if (!l.empty() && l.back() == '\r') {
            l.remove_suffix(1);
        }
        if (!l.empty() && l.back() == '\\') {
            if (joined.empty()) {
                joinedFrom = line;
            }
            joined.append(l.substr(0, l.size() - 1)).push_back(' ');
            return;
        }
        std::string_view logical = l;
        std::size_t from = line;
        if (!joined.empty()) {
            joined.append(l);
            logical = joined;
            from = joinedFrom;
        }
        if (const std::size_t hash = logical.find('#'); hash != std::string_view::npos) {
            logical = logical.substr(0, hash);
        }
        f(from, logical);
        joined.clear();
    });
    if (!joined.empty()) {
        f(joinedFrom, std::string_view(joined));
    }
}

/// The index `part` of `token` as the file writes it (1-based, or negative counting back from
/// the `soFar` items before this line), refused with the line unless it names one of `total`.
std::int64_t checkObjIndex(std::string_view token, std::string_view part, const char* what,
                           const char* plural, std::int64_t total, std::int64_t soFar,
                           const std::string& name, std::size_t line) {
    const auto place = [&] { return atLine(name, line); };
    const auto i = parseInteger(part);
    if (!i) {
        fail(place() + "'" + std::string(part) + "' in " + quoted(token) + " is not a " + what +
             " index (a whole number)");
    }
    if (*i == 0) {
        fail(place() + what + " index 0 in " + quoted(token) + ": indices start at 1");
    }
    if (*i > total) {
        fail(place() + what + " index " + std::to_string(*i) + " is out of range (the file has " +
             std::to_string(total) + " " + plural + ")");
    }
    if (*i < 0 && *i < -soFar) { // not -*i: INT64_MIN has no negation
        fail(place() + "relative " + what + " index " + std::to_string(*i) +
             " is out of range (only " + std::to_string(soFar) + " " + plural +
             " come before this line)");
    }
    return *i;
}

/// Refuses a line that assimp 5.2.5's OBJ reader read otherwise than the specification (still
/// refused, so every file hapto loads reads as it did then): it took a statement from the line's
/// first character, with no space skipped, so it drops an indented `v` or `f` (shifting every index
/// after it), reads any word that begins with `f`, `l` or `p` as a face, line or point and one that
/// begins with `vt` or `vn` as those, and takes a vertex only when a space or a tab follows the
/// `v`.
template <class Place>
void refuseAssimpMisreads(std::string_view line, std::string_view key, const Place& place) {
    const bool geometry =
        key == "v" || key == "vt" || key == "vn" || key == "f" || key == "l" || key == "p";
    if (key.data() != line.data()) {
        if (geometry) {
            fail(place() + "an indented '" + std::string(key) +
                 "' statement (other readers, assimp among them, skip a line that does "
                 "not begin with its statement, which would lose it): remove the indentation");
        }
        return;
    }
    if (!geometry && key != "vp" &&
        (key[0] == 'f' || key[0] == 'l' || key[0] == 'p' || key.starts_with("vt") ||
         key.starts_with("vn"))) {
        fail(place() + quoted(key) +
             " is not an OBJ geometry statement, but other readers (assimp) would read it as one "
             "(a word beginning with f, l, p, vt or vn)");
    }
    if (key == "v" && line.size() > 1 && line[1] != ' ' && line[1] != '\t') {
        fail(place() + "'v' must be followed by a space or a tab");
    }
}

/// A `v` line's x y z [w], already read as numbers: each coordinate passes floatProblem, a
/// weight w is not 0 as a float (x y z are divided by it, in floats, as assimp 5.2.5 did), and
/// every x / w passes coordinateProblem at `scale`. Returns the position, in floats.
template <class Place>
Vec3 checkObjVertex(const std::vector<std::string_view>& tok, double scale, const Place& place) {
    double w = 1.0;
    if (tok.size() == 5) {
        w = *parseNumber(tok[4]);
        if (const std::string p = floatProblem(w); !p.empty()) {
            fail(place() + "the vertex's weight w " + quoted(tok[4]) + " " + p);
        }
        if (static_cast<float>(w) == 0.0f) {
            fail(place() + "the vertex's weight w is 0" +
                 (w == 0.0 ? std::string() : " as a 32-bit float (" + quoted(tok[4]) + ")") +
                 " (x y z are divided by it)");
        }
    }
    for (std::size_t k = 1; k <= 3; ++k) {
        const double v = *parseNumber(tok[k]);
        std::string p = floatProblem(v);
        if (p.empty()) {
            p = coordinateProblem(v / w, scale);
            if (!p.empty() && tok.size() == 5) {
                p = "divided by the weight w " + quoted(tok[4]) + " " + p;
            }
        }
        if (!p.empty()) {
            fail(place() + "vertex coordinate " + quoted(tok[k]) + " " + p);
        }
    }
    const auto f = [&](std::size_t k) {
        return static_cast<double>(static_cast<float>(*parseNumber(tok[k])) /
                                   static_cast<float>(w));
    };
    return {f(1), f(2), f(3)};
}

/// Refuses the characters assimp 5.2.5 read otherwise than this reader: it ended a line at a
/// carriage return or a form feed, so one inside a line would split its statement, and does
/// not take a vertical tab for a space, so one would join two words.
void checkObjCharacters(std::string_view text, const std::string& name) {
    for (std::size_t i = text.find_first_of("\r\f\v"); i != std::string_view::npos;
         i = text.find_first_of("\r\f\v", i + 1)) {
        if (text[i] != '\r' || (i + 1 < text.size() && text[i + 1] != '\n')) {
            const auto line = 1 + std::count(text.begin(), text.begin() + i, '\n');
            fail(atLine(name, static_cast<std::size_t>(line)) +
                 (text[i] == '\v'
                      ? "a vertical tab (other readers (assimp) would not read it as a space but "
                        "as part of a word; separate values with spaces or tabs)"
                  : text[i] == '\f'
                      ? "a form feed inside a line (other readers (assimp) would end the line "
                        "there; lines end with \\n or \\r\\n)"
                      : "a carriage return inside a line (other readers (assimp) would end the "
                        "line there; lines end with \\n or \\r\\n)"));
        }
    }
}

/// One pass over an OBJ text's statements, keeping its vertices and faces.
class ObjWalk {
    /// A lambda giving "NAME:LINE: " for the statement being read.
    auto place() const {
        return [this] { return atLine(mName, mLine); };
    }

public:
    ObjWalk(const std::string& name, double scale, ObjCounts total)
        : mName(name), mScale(scale), mTotal(total) {
        mModel.vertices.reserve(static_cast<std::size_t>(total.v));
        mUsed.assign(static_cast<std::size_t>(total.v), false);
    }

    /// Reads one logical line (continuations joined, comment cut) that begins on `lineNo`.
    void statement(std::size_t lineNo, std::string_view line) {
        tokens(line, mTok);
        if (mTok.empty()) {
            return;
        }
        mLine = lineNo;
        const std::string_view key = mTok[0];
        refuseAssimpMisreads(line, key, place());
        if (key == "v") {
            numbers({3, 4, 6}, "x y z, x y z w or x y z r g b");
            mModel.vertices.push_back(checkObjVertex(mTok, mScale, place()));
            ++mSeen.v;
        } else if (key == "vt") {
            numbers({2, 3}, "u v or u v w");
            ++mSeen.vt;
        } else if (key == "vn") {
            numbers({3}, "i j k");
            ++mSeen.vn;
        } else if (key == "f" || key == "l" || key == "p") {
            element(key);
        }
    }

    /// The model: the vertices a face, line or point names (in file order), and the faces.
    ModelFaces finish() {
        if (mTriangles == 0) {
            fail(mName + ": no triangles (no 'f' line)");
        }
        std::vector<std::uint32_t> remap(mModel.vertices.size());
        std::size_t kept = 0;
        for (std::size_t i = 0; i < mModel.vertices.size(); ++i) {
            remap[i] = static_cast<std::uint32_t>(kept);
            if (mUsed[i]) {
                mModel.vertices[kept++] = mModel.vertices[i];
            }
        }
        mModel.vertices.resize(kept);
        for (std::uint32_t& c : mModel.corners) {
            c = remap[c];
        }
        return std::move(mModel);
    }

private:
    /// x y z, x y z w or x y z r g b (assimp skipped a vertex of any other count, which shifts
    /// every index after it); u [v [w]] with v (assimp threw on one); i j k.
    void numbers(std::initializer_list<std::size_t> counts, const char* forms) const {
        const std::size_t n = mTok.size() - 1;
        if (std::find(counts.begin(), counts.end(), n) == counts.end()) {
            fail(atLine(mName, mLine) + "'" + std::string(mTok[0]) + "' takes " + forms + ", got " +
                 std::to_string(n) + " numbers");
        }
        for (std::size_t k = 1; k < mTok.size(); ++k) {
            const auto v = parseNumber(mTok[k]);
            if (!v) {
                fail(atLine(mName, mLine) + quoted(mTok[k]) + " is not a number");
            }
            // assimp counted the numbers of a v or vt only when they begin with a digit or a
            // sign (or are NaN or infinite): ".5" would have made it one number short.
            const char c = mTok[k][0];
            if (mTok[0] != "vn" && std::isfinite(*v) && (c < '0' || c > '9') && c != '+' &&
                c != '-') {
                fail(atLine(mName, mLine) + quoted(mTok[k]) +
                     " does not begin with a digit or a sign (other readers (assimp) would not "
                     "count it; write 0.5 for .5)");
            }
        }
    }

    /// An `f`, `l` or `p`: its indices checked, a face's corners kept. Lines and points make
    /// no triangles, but the vertices they name stay in the model (as assimp kept them).
    void element(std::string_view key) {
        const std::size_t least = key == "f" ? 3 : key == "l" ? 2 : 1;
        const char* what = key == "f" ? "face" : key == "l" ? "line" : "point";
        if (mTok.size() < least + 1) {
            fail(atLine(mName, mLine) + "a " + what + " needs at least " + std::to_string(least) +
                 " vertices, got " + std::to_string(mTok.size() - 1));
        }
        checkFaceSize(mTok.size() - 1, atLine(mName, mLine), what);
        for (std::size_t k = 1; k < mTok.size(); ++k) {
            const auto v = static_cast<std::uint32_t>(corner(mTok[k]));
            mUsed[v] = true;
            if (key == "f") {
                mModel.corners.push_back(v);
            }
        }
        if (key == "f") {
            mModel.faceSizes.push_back(static_cast<std::uint16_t>(mTok.size() - 1));
            mTriangles += mTok.size() - 3;
            checkTriangleLimit(mTriangles, mName);
        }
    }

    /// A corner `v[/vt][/vn]`: its indices checked; the vertex's 0-based index.
    std::int64_t corner(std::string_view t) const {
        const std::size_t s1 = t.find('/');
        const std::int64_t v = checkObjIndex(t, t.substr(0, s1), "vertex", "vertices", mTotal.v,
                                             mSeen.v, mName, mLine);
        if (s1 != std::string_view::npos) {
            const std::size_t s2 = t.find('/', s1 + 1);
            const std::string_view vt = t.substr(s1 + 1, s2 - (s1 + 1));
            if (!vt.empty()) {
                checkObjIndex(t, vt, "texture coordinate", "texture coordinates", mTotal.vt,
                              mSeen.vt, mName, mLine);
            }
            if (s2 != std::string_view::npos) {
                checkObjIndex(t, t.substr(s2 + 1), "normal", "normals", mTotal.vn, mSeen.vn, mName,
                              mLine);
            }
        }
        return v > 0 ? v - 1 : mSeen.v + v;
    }

    const std::string& mName;
    double mScale;
    ObjCounts mTotal;
    ObjCounts mSeen;
    std::size_t mLine = 0;
    std::uint64_t mTriangles = 0;
    std::vector<std::string_view> mTok;
    ModelFaces mModel;
    std::vector<bool> mUsed; ///< Per vertex: named by a face, line or point.
};

} // namespace

void blankObjComments(std::string& text) {
    for (std::size_t i = text.find('#'); i != std::string::npos; i = text.find('#', i)) {
        for (; i < text.size() && text[i] != '\n' && text[i] != '\r' && text[i] != '\0'; ++i) {
            text[i] = ' ';
        }
    }
}

ModelFaces readObj(std::string_view text, const std::string& name, double scale) {
    refuseNul(text, name, "an OBJ text file");
    checkObjCharacters(text, name);
    std::vector<std::string_view> tok;
    ObjCounts total;
    forEachObjLine(text, [&](std::size_t, std::string_view line) {
        tokens(line, tok);
        if (tok.empty()) {
            return;
        }
        total.v += tok[0] == "v";
        total.vt += tok[0] == "vt";
        total.vn += tok[0] == "vn";
    });
    if (total.v > static_cast<std::int64_t>(TriangleMesh::kMaxVertices)) {
        fail(name + ": " + std::to_string(total.v) + " vertices; a mesh may have at most " +
             std::to_string(TriangleMesh::kMaxVertices));
    }
    ObjWalk walk(name, scale, total);
    forEachObjLine(
        text, [&](std::size_t lineNo, std::string_view line) { walk.statement(lineNo, line); });
    return walk.finish();
}

} // namespace hapto::detail
