// gnuplot scripts for `hapto experiment` figures.

#include "hapto/experiments/Plot.h"

#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/io/OutputFile.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace hapto::experiments {
namespace {

/// A gnuplot string constant holding `s` as plain text, in ASCII: double-quoted, with every byte
/// that could mean anything to gnuplot written as an octal escape (\ooo): the quotes, the
/// backslash, the backquote (gnuplot runs `...` as a shell command even inside a string), @
/// (macros), $, and every byte outside printable ASCII. Control characters are first made
/// visible by json::printable (a newline shows as \n), so no name or path can end a command.
/// (Single quotes would need no escapes, but gnuplot 5.4 misreads '' at a string's start or
/// twice in a row, e.g. '''a'.)
std::string quoted(const std::string& s) {
    constexpr std::string_view kSpecial = "\"\\`@$'";
    std::string q = "\"";
    for (const char ch : json::printable(s)) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x20 || c > 0x7E || kSpecial.find(ch) != std::string_view::npos) {
            q += {'\\', static_cast<char>('0' + (c >> 6)), static_cast<char>('0' + ((c >> 3) & 7)),
                  static_cast<char>('0' + (c & 7))};
        } else {
            q += ch;
        }
    }
    return q + "\"";
}

bool usable(const PlotPanel& p, const std::pair<double, double>& xy) {
    return std::isfinite(xy.first) && std::isfinite(xy.second) && (!p.logX || xy.first > 0) &&
           (!p.logY || xy.second > 0);
}

/// The y range of the panels' data and limit lines (log panels: positive values only).
std::optional<std::pair<double, double>> dataRange(const std::vector<const PlotPanel*>& panels) {
    std::optional<std::pair<double, double>> range;
    const auto take = [&](double y) {
        range = range ? std::pair{std::min(range->first, y), std::max(range->second, y)}
                      : std::pair{y, y};
    };
    for (const PlotPanel* p : panels) {
        for (const PlotSeries& series : p->series) {
            for (std::size_t q = 0; q < series.points.size(); ++q) {
                const auto& xy = series.points[q];
                if (usable(*p, xy)) {
                    take(xy.second);
                    if (q < series.errors.size()) { // the bars' ends too, where the axis shows them
                        for (const double e : {series.errors[q].first, series.errors[q].second}) {
                            if (usable(*p, {xy.first, e})) {
                                take(e);
                            }
                        }
                    }
                }
            }
        }
        if (p->limitY && (!p->logY || *p->limitY > 0)) {
            take(*p->limitY);
        }
    }
    return range;
}

/// `range` widened so that points and lines do not sit on the frame.
std::pair<double, double> widened(std::pair<double, double> range, bool logY) {
    if (logY) {
        return {range.first / 2.0, range.second * 2.0};
    }
    const double pad = std::max(1e-9, 0.1 * (range.second - range.first));
    return {std::min(0.0, range.first - pad), range.second + pad};
}

std::string number(double v) {
    char text[48];
    std::snprintf(text, sizeof text, "%.9g", v);
    return text;
}

/// " LO HI" for point q of a series with error bars (the point itself where it has none, or
/// where a log axis cannot show the end); empty for a series without bars.
std::string errorColumns(const PlotPanel& p, const PlotSeries& series, std::size_t q) {
    if (series.errors.empty()) {
        return {};
    }
    const double y = series.points[q].second;
    double lo = y, hi = y;
    if (q < series.errors.size()) {
        lo = series.errors[q].first;
        hi = series.errors[q].second;
    }
    if (!std::isfinite(lo) || (p.logY && lo <= 0)) {
        lo = y;
    }
    if (!std::isfinite(hi)) {
        hi = y;
    }
    return " " + number(lo) + " " + number(hi);
}

/// A data block's name: panel i, series k ("$d0_1"), or the unstable marks of panel i ("$u0").
std::string blockName(std::size_t i, std::size_t k) {
    return "$d" + std::to_string(i) + "_" + std::to_string(k);
}

/// `title` (a quoted gnuplot string) followed by the spec's caption on a line of its own.
std::string withCaption(const std::string& title, const PlotSpec& spec) {
    return spec.caption.empty() ? title : title + ".\"\\n\"." + quoted(spec.caption);
}

/// How many key entries the panel's spans add.
std::size_t spanKeys(const PlotPanel& p) {
    if (p.spans.empty()) {
        return 0;
    }
    if (p.spanStyles.empty()) {
        return p.spanTitle.empty() ? 0 : 1;
    }
    std::vector<int> styles(p.spanStyles);
    std::sort(styles.begin(), styles.end());
    styles.erase(std::unique(styles.begin(), styles.end()), styles.end());
    return static_cast<std::size_t>(std::count_if(styles.begin(), styles.end(), [&](int st) {
        return st >= 1 && static_cast<std::size_t>(st) <= p.spanStyleTitles.size();
    }));
}

/// Sets the panel's shaded spans as rectangles behind the data (grey, or per style a
/// translucent colour) and returns their key entries (boxes of their colour drawn nowhere).
std::vector<std::string> spanPlots(std::ostringstream& s, const PlotPanel& p) {
    std::vector<std::string> keys;
    for (std::size_t k = 0; k < p.spans.size(); ++k) {
        const bool styled = k < p.spanStyles.size();
        s << "set object " << k + 1 << " rect from " << number(p.spans[k].first) << ", graph 0 to "
          << number(p.spans[k].second) << ", graph 1 behind fillcolor rgb '"
          << (styled ? plotColour(p.spanStyles[k]) : std::string("#dddddd"))
          << (styled ? "' fillstyle transparent solid 0.18 noborder\n"
                     : "' fillstyle solid 1.0 noborder\n");
    }
    if (p.spans.empty()) {
        return keys;
    }
    if (p.spanStyles.empty()) {
        if (!p.spanTitle.empty()) {
            keys.push_back("keyentry with boxes fillcolor rgb '#dddddd' fillstyle solid 1.0 "
                           "title " +
                           quoted(p.spanTitle));
        }
        return keys;
    }
    for (std::size_t st = 1; st <= p.spanStyleTitles.size(); ++st) {
        if (std::find(p.spanStyles.begin(), p.spanStyles.end(), static_cast<int>(st)) !=
            p.spanStyles.end()) {
            keys.push_back(
                "keyentry with boxes fillcolor rgb '" + plotColour(static_cast<int>(st)) +
                "' fillstyle transparent solid 0.18 title " + quoted(p.spanStyleTitles[st - 1]));
        }
    }
    return keys;
}

/// The plot clause of series k of a panel, drawn from `block`: colour and point type by style
/// (or position), so a series keeps its look in every panel even when another has no points
/// there; error bars when it has them; joined unless points only.
std::string seriesPlot(const std::string& block, const PlotSeries& series, std::size_t k) {
    const int style = series.style > 0 ? series.style : static_cast<int>(k) + 1;
    const bool bars = !series.errors.empty();
    std::string with;
    if (series.linesOnly) {
        with = "lines";
    } else if (bars) {
        with = series.pointsOnly ? "yerrorbars" : "yerrorlines";
    } else {
        with = series.pointsOnly ? "points" : "linespoints";
    }
    return block + (bars ? " using 1:2:3:4" : " using 1:2") + " with " + with + " lc rgb '" +
           plotColour(style) + "'" +
           (series.linesOnly ? "" : " pt " + std::to_string((style - 1) % 13 + 1) + " ps 1.3") +
           " lw 1.5 dt " +
           std::to_string(series.dash > 0 ? series.dash
                          : series.dashed ? 2
                                          : 1) +
           " title " + quoted(series.title);
}

std::string body(const PlotSpec& spec, const std::vector<std::vector<std::string>>& blocks,
                 const std::vector<std::string>& unstableBlocks) {
    std::ostringstream s;
    const bool multi = spec.panels.size() > 1;
    const std::size_t columns =
        spec.columns > 0 ? std::min<std::size_t>(static_cast<std::size_t>(spec.columns),
                                                 std::max<std::size_t>(1, spec.panels.size()))
                         : std::max<std::size_t>(1, spec.panels.size());
    const std::size_t rows = (spec.panels.size() + columns - 1) / columns;
    if (multi) {
        s << "set multiplot layout " << rows << "," << columns << " title "
          << withCaption(quoted(spec.title), spec) << "\n";
    }
    const std::optional<std::pair<double, double>> shared = sharedYRange(spec);
    for (std::size_t i = 0; i < spec.panels.size(); ++i) {
        const PlotPanel& p = spec.panels[i];
        s << "set title "
          << (multi
                  ? quoted(p.title)
                  : withCaption(quoted(spec.title + (p.title.empty() ? "" : ": ") + p.title), spec))
          << "\n";
        s << "set xlabel " << quoted(p.xLabel) << "\nset ylabel " << quoted(p.yLabel) << "\n";
        s << (p.logX ? "set logscale x\n" : "unset logscale x\n");
        s << (p.logY ? "set logscale y\n" : "unset logscale y\n");
        s << "set grid\nset key below\n";
        if (!p.xTics.empty()) {
            // A labelled tic at every measured x (each device count, each size).
            s << "set xtics (";
            for (std::size_t k = 0; k < p.xTics.size(); ++k) {
                const std::string label =
                    k < p.xTicLabels.size() ? p.xTicLabels[k] : number(p.xTics[k]);
                s << (k ? ", " : "") << quoted(label) << " " << number(p.xTics[k]);
            }
            s << ")\n";
            if (!p.logX) {
                // Half the smallest step of room either side: the outer points and bars show whole.
                std::vector<double> x(p.xTics);
                std::sort(x.begin(), x.end());
                double gap = x.size() > 1 ? x.back() - x.front() : 1.0;
                for (std::size_t k = 1; k < x.size(); ++k) {
                    gap = x[k] > x[k - 1] ? std::min(gap, x[k] - x[k - 1]) : gap;
                }
                const double* lo = &x.front();
                const double* hi = &x.back();
                const double pad = 0.5 * gap; // categories (devices) sit half a step in
                s << "set xrange [" << number(*lo - pad) << ":" << number(*hi + pad) << "]\n";
            } else {
                const auto [lo, hi] = std::minmax_element(p.xTics.begin(), p.xTics.end());
                s << (*lo > 0 ? "set xrange [" + number(*lo / 1.4) + ":" + number(*hi * 1.4) + "]\n"
                              : std::string("set xrange [*:*]\n"));
            }
        } else {
            s << "set xtics autofreq\nset xrange [*:*]\n";
        }
        std::optional<std::pair<double, double>> range = spec.shareY ? shared : dataRange({&p});
        if (range) {
            const auto [lo, hi] = widened(*range, p.logY);
            s << "set yrange [" << number(lo) << ":" << number(hi) << "]\n";
        } else {
            s << "set yrange [*:*]\n";
        }
        s << "unset object\n";
        std::vector<std::string> plots = spanPlots(s, p);
        for (std::size_t k = 0; k < blocks[i].size(); ++k) {
            if (!blocks[i][k].empty()) {
                // Colour and point type by style (or series position), so a series keeps its
                // look in every panel even when another series has no points there.
                plots.push_back(seriesPlot(blocks[i][k], p.series[k], k));
            }
        }
        if (!unstableBlocks[i].empty()) {
            plots.push_back(unstableBlocks[i] +
                            " using 1:2 with points pt 6 ps 2.2 lw 2 lc rgb 'black' title " +
                            quoted(spec.unstableTitle));
        }
        if (p.limitY) {
            plots.push_back(number(*p.limitY) + " with lines dt 3 lc rgb 'red' title " +
                            quoted(p.limitTitle));
        }
        const std::size_t decorations = (p.limitY ? 1u : 0u) + spanKeys(p);
        if (plots.empty() || plots.size() == decorations) {
            s << "set label 1 'no data' at graph 0.5, 0.5 center\n";
            plots = {"[1:10] [1:2] 3 notitle"}; // above the range (log axes too): nothing drawn
        }
        s << "plot ";
        for (std::size_t k = 0; k < plots.size(); ++k) {
            s << (k ? ", \\\n     " : "") << plots[k];
        }
        s << "\nunset label 1\n";
    }
    if (multi) {
        s << "unset multiplot\n";
    }
    s << "unset object\n";
    return s.str();
}

/// The gnuplot executable on PATH (an absolute path), if any.
std::optional<std::filesystem::path> gnuplotPath() {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const std::filesystem::path exe =
            std::filesystem::path(dir.empty() ? "." : dir) / "gnuplot";
        if (access(exe.c_str(), X_OK) == 0) {
            std::error_code ec;
            const std::filesystem::path absolute = std::filesystem::absolute(exe, ec);
            return ec ? exe : absolute; // gnuplot starts in another folder
        }
    }
    return std::nullopt;
}

/// Runs `gnuplot -e "out='OUT'" SCRIPT` in `dir`, started directly (fork and execv, no shell),
/// its output to `log`: the only text it reads as code is the script and `outStem`, a name
/// hapto made. Returns gnuplot's exit code, -1 when it could not start or died on a signal.
int runGnuplot(const std::filesystem::path& dir, const std::string& script,
               const std::string& outStem, const std::filesystem::path& log) {
    const std::optional<std::filesystem::path> exe = gnuplotPath();
    if (!exe) {
        return -1;
    }
    std::string program = "gnuplot", e = "-e", define = "out=" + quoted(outStem);
    std::string file = "./" + script; // never read as an option
    std::array<char*, 5> argv = {program.data(), e.data(), define.data(), file.data(), nullptr};
    const int logFd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int nullFd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (logFd < 0 || nullFd < 0) {
        ::close(logFd);
        ::close(nullFd);
        return -1;
    }
    const pid_t pid = ::fork();
    if (pid == 0) {
        // The child: only async-signal-safe calls until execv.
        if (::chdir(dir.c_str()) == 0 && ::dup2(nullFd, 0) == 0 && ::dup2(logFd, 1) == 1 &&
            ::dup2(logFd, 2) == 2) {
            ::execv(exe->c_str(), argv.data());
        }
        ::_exit(127);
    }
    ::close(logFd);
    ::close(nullFd);
    int status = 0;
    if (pid < 0) {
        return -1;
    }
    while (::waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) {
            return -1;
        }
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A name for temporaries no other drawing in this or another process uses at the same time.
std::string temporaryStem() {
    static std::atomic<unsigned> counter{0};
    return ".hapto-plot.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

} // namespace

std::string plotColour(int style) {
    static constexpr const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                               "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                               "#bcbd22", "#17becf"};
    const int n = static_cast<int>(std::size(kPalette));
    return kPalette[((style - 1) % n + n) % n];
}

bool gnuplotAvailable() {
    return gnuplotPath().has_value();
}

std::optional<std::pair<double, double>> sharedYRange(const PlotSpec& spec) {
    std::vector<const PlotPanel*> panels;
    for (const PlotPanel& p : spec.panels) {
        panels.push_back(&p);
    }
    return dataRange(panels);
}

std::string plotScript(const PlotSpec& spec) {
    std::ostringstream script;
    script << "# " << quoted(spec.title) << " (generated by hapto; run: gnuplot "
           << json::printable(spec.name) << ".gp)\n";
    // Data as datablocks, one per series, and one per panel for its unstable points.
    std::vector<std::vector<std::string>> blocks(spec.panels.size());
    std::vector<std::string> unstableBlocks(spec.panels.size());
    for (std::size_t i = 0; i < spec.panels.size(); ++i) {
        const PlotPanel& p = spec.panels[i];
        std::ostringstream marks;
        for (std::size_t k = 0; k < p.series.size(); ++k) {
            std::ostringstream data;
            std::size_t n = 0;
            for (std::size_t q = 0; q < p.series[k].points.size(); ++q) {
                const auto& xy = p.series[k].points[q];
                if (usable(p, xy)) {
                    const std::string line = number(xy.first) + " " + number(xy.second);
                    data << line << errorColumns(p, p.series[k], q) << "\n";
                    ++n;
                    if (q < p.series[k].unstable.size() && p.series[k].unstable[q]) {
                        marks << line << "\n";
                    }
                }
            }
            if (n == 0) {
                blocks[i].emplace_back();
                continue;
            }
            const std::string name = blockName(i, k);
            script << name << " << EOD\n" << data.str() << "EOD\n";
            blocks[i].push_back(name);
        }
        if (!marks.str().empty()) {
            unstableBlocks[i] = "$u" + std::to_string(i);
            script << unstableBlocks[i] << " << EOD\n" << marks.str() << "EOD\n";
        }
    }
    const std::size_t n = std::max<std::size_t>(1, spec.panels.size());
    const std::size_t columns =
        spec.columns > 0 ? std::min<std::size_t>(static_cast<std::size_t>(spec.columns), n) : n;
    const int width = spec.panelWidthPx * static_cast<int>(columns);
    const int height = spec.heightPx * static_cast<int>((n + columns - 1) / columns);
    const std::string plot = body(spec, blocks, unstableBlocks);
    // `out` names the images without their extension; hapto sets it (gnuplot -e) to a
    // temporary name and renames the finished images into place, so a figure is never half
    // written. Run by hand, the script writes NAME.png and NAME.svg directly.
    script << "if (!exists(\"out\")) out = " << quoted(spec.name) << "\n";
    if (spec.png) {
        script << "set terminal pngcairo size " << width << "," << height
               << " noenhanced font 'sans,10'\nset output out.\".png\"\n"
               << plot << "set output\n";
    }
    if (spec.svg) {
        script << "set terminal svg size " << width << "," << height
               << " noenhanced font 'sans,10'\nset output out.\".svg\"\n"
               << plot << "set output\n";
    }
    return script.str();
}

PlotResult drawPlot(const std::filesystem::path& dir, const PlotSpec& spec) {
    PlotResult r;
    const std::filesystem::path gp = dir / (spec.name + ".gp");
    try {
        writeFileAtomically(gp, plotScript(spec));
    } catch (const std::exception& e) {
        r.problem = e.what();
        return r;
    }
    if (!gnuplotAvailable()) {
        r.problem = "gnuplot not found on PATH (Debian: apt-get install gnuplot-nox); wrote " +
                    gp.string() + " without drawing it";
        return r;
    }
    const std::string log = spec.name + ".gp.log";
    const std::string temporary = temporaryStem();
    const int status = runGnuplot(dir, spec.name + ".gp", temporary, dir / log);
    const auto dropTemporaries = [&] {
        std::error_code ignored;
        for (const char* ext : {".png", ".svg"}) {
            std::filesystem::remove(dir / (temporary + ext), ignored);
        }
    };
    if (status != 0) {
        dropTemporaries();
        r.problem = "gnuplot failed on " + gp.string() + " (exit " + std::to_string(status) +
                    "; see " + (dir / log).string() + ")";
        return r;
    }
    std::error_code ec;
    std::filesystem::remove(dir / log, ec);
    for (const char* ext : {".png", ".svg"}) {
        const std::filesystem::path made = dir / (temporary + ext);
        const std::filesystem::path f = dir / (spec.name + ext);
        if (std::filesystem::exists(made)) {
            std::filesystem::rename(made, f, ec); // whole, in one step
            if (ec) {
                r.problem =
                    "cannot rename " + made.string() + " to " + f.string() + ": " + ec.message();
                dropTemporaries();
                return r;
            }
            r.files.push_back(f);
        }
    }
    if (r.files.empty()) {
        r.problem = "gnuplot made no file from " + gp.string();
    }
    return r;
}

void drawPlotFile(const PlotSpec& spec, const std::filesystem::path& out,
                  const std::filesystem::path& script) {
    const std::string ext = out.extension().string();
    if (ext != ".png" && ext != ".svg") {
        throw InputError(out.string() + ": the plot file's name must end in .png or .svg (got \"" +
                         ext + "\")");
    }
    PlotSpec one = spec;
    one.png = ext == ".png";
    one.svg = ext == ".svg";
    const std::string text = plotScript(one);
    if (!script.empty()) {
        writeFileAtomically(script, text);
    }
    if (!gnuplotAvailable()) {
        throw std::runtime_error(
            "gnuplot not found on PATH (Debian: apt-get install gnuplot-nox); nothing drawn" +
            (script.empty() ? std::string() : ", wrote " + script.string()));
    }
    // Script, log and image all go to temporaries beside `out` (same file system: the final
    // rename is one step), named by hapto: gnuplot runs in that folder and never sees `out`.
    const std::filesystem::path dir =
        out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();
    const std::string stem = temporaryStem();
    const std::filesystem::path gp = dir / (stem + ".gp");
    const std::filesystem::path log = dir / (stem + ".log");
    const std::filesystem::path image = dir / (stem + ext);
    std::error_code ignored;
    const auto cleanUp = [&] {
        std::filesystem::remove(gp, ignored);
        std::filesystem::remove(log, ignored);
        std::filesystem::remove(image, ignored);
    };
    {
        std::ofstream f(gp, std::ios::binary | std::ios::trunc);
        f << text;
        if (!f.flush()) {
            cleanUp();
            throw std::runtime_error(gp.string() + ": cannot write the plot script");
        }
    }
    const int status = runGnuplot(dir, stem + ".gp", stem, log);
    if (status != 0 || !std::filesystem::exists(image)) {
        std::string why;
        std::ifstream in(log);
        std::getline(in, why);
        cleanUp();
        throw std::runtime_error("gnuplot failed drawing " + json::printable(out.string()) +
                                 " (exit " + std::to_string(status) +
                                 (why.empty() ? "" : ": " + json::printable(why)) + ")");
    }
    std::error_code ec;
    std::filesystem::rename(image, out, ec); // whole, in one step
    cleanUp();
    if (ec) {
        throw std::runtime_error("cannot rename the plot into " + out.string() + ": " +
                                 ec.message());
    }
}

} // namespace hapto::experiments
