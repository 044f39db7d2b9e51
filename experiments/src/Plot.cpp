// gnuplot scripts for `hapto experiment` figures.

#include "hapto/experiments/Plot.h"

#include "hapto/scenes/InputError.h"
#include "hapto/scenes/OutputFile.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace hapto::experiments {
namespace {

/// Quotes a string for gnuplot's double-quoted strings.
std::string gq(const std::string& s) {
    std::string q = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') {
            q += '\\';
        }
        q += c;
    }
    return q + "\"";
}

/// Quotes a string for /bin/sh.
std::string shq(const std::string& s) {
    std::string q = "'";
    for (const char c : s) {
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    }
    return q + "'";
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
            for (const auto& xy : series.points) {
                if (usable(*p, xy)) {
                    take(xy.second);
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

/// A data block's name: panel i, series k ("$d0_1"), or the unstable marks of panel i ("$u0").
std::string blockName(std::size_t i, std::size_t k) {
    return "$d" + std::to_string(i) + "_" + std::to_string(k);
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
        s << "set multiplot layout " << rows << "," << columns << " title " << gq(spec.title)
          << "\n";
    }
    const std::optional<std::pair<double, double>> shared = sharedYRange(spec);
    for (std::size_t i = 0; i < spec.panels.size(); ++i) {
        const PlotPanel& p = spec.panels[i];
        s << "set title "
          << gq(multi ? p.title : spec.title + (p.title.empty() ? "" : ": ") + p.title) << "\n";
        s << "set xlabel " << gq(p.xLabel) << "\nset ylabel " << gq(p.yLabel) << "\n";
        s << (p.logX ? "set logscale x\n" : "unset logscale x\n");
        s << (p.logY ? "set logscale y\n" : "unset logscale y\n");
        s << "set grid\nset key below\n";
        if (!p.xTics.empty()) {
            // A labelled tic at every measured x (each device count, each size).
            s << "set xtics (";
            for (std::size_t k = 0; k < p.xTics.size(); ++k) {
                const std::string label =
                    k < p.xTicLabels.size() ? p.xTicLabels[k] : number(p.xTics[k]);
                s << (k ? ", " : "") << gq(label) << " " << number(p.xTics[k]);
            }
            s << ")\n";
        } else {
            s << "set xtics autofreq\n";
        }
        std::optional<std::pair<double, double>> range = spec.shareY ? shared : dataRange({&p});
        if (range) {
            const auto [lo, hi] = widened(*range, p.logY);
            s << "set yrange [" << number(lo) << ":" << number(hi) << "]\n";
        } else {
            s << "set yrange [*:*]\n";
        }
        s << "unset object\n";
        for (std::size_t k = 0; k < p.spans.size(); ++k) {
            s << "set object " << k + 1 << " rect from " << number(p.spans[k].first)
              << ", graph 0 to " << number(p.spans[k].second)
              << ", graph 1 behind fillcolor rgb '#dddddd' fillstyle solid 1.0 noborder\n";
        }
        std::vector<std::string> plots;
        if (!p.spans.empty() && !p.spanTitle.empty()) {
            // A key entry for the shading (a box of its colour drawn nowhere).
            plots.push_back("keyentry with boxes fillcolor rgb '#dddddd' fillstyle solid 1.0 "
                            "title " +
                            gq(p.spanTitle));
        }
        for (std::size_t k = 0; k < blocks[i].size(); ++k) {
            if (!blocks[i][k].empty()) {
                // Colour and point type by style (or series position), so a series keeps its
                // look in every panel even when another series has no points there.
                const PlotSeries& series = p.series[k];
                const int style = series.style > 0 ? series.style : static_cast<int>(k) + 1;
                plots.push_back(blocks[i][k] + " using 1:2 with " +
                                (series.linesOnly ? "lines" : "linespoints") + " lc " +
                                std::to_string(style) +
                                (series.linesOnly ? "" : " pt " + std::to_string(style)) +
                                (series.dashed ? " dt 2" : " dt 1") + " title " + gq(series.title));
            }
        }
        if (!unstableBlocks[i].empty()) {
            plots.push_back(unstableBlocks[i] +
                            " using 1:2 with points pt 6 ps 2.2 lw 2 lc rgb 'black' title " +
                            gq(spec.unstableTitle));
        }
        if (p.limitY) {
            plots.push_back(number(*p.limitY) + " with lines dt 3 lc rgb 'red' title " +
                            gq(p.limitTitle));
        }
        const std::size_t decorations =
            (p.limitY ? 1u : 0u) + (!p.spans.empty() && !p.spanTitle.empty() ? 1u : 0u);
        if (plots.empty() || plots.size() == decorations) {
            s << "set label 1 'no data' at graph 0.5, 0.5 center\n";
            plots = {"[1:10] 1/0 notitle"};
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

} // namespace

bool gnuplotAvailable() {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const std::filesystem::path exe =
            std::filesystem::path(dir.empty() ? "." : dir) / "gnuplot";
        if (access(exe.c_str(), X_OK) == 0) {
            return true;
        }
    }
    return false;
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
    script << "# " << spec.title << " (generated by hapto experiment; run: gnuplot " << spec.name
           << ".gp)\n";
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
                    const std::string line = number(xy.first) + " " + number(xy.second) + "\n";
                    data << line;
                    ++n;
                    if (q < p.series[k].unstable.size() && p.series[k].unstable[q]) {
                        marks << line;
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
    script << "if (!exists(\"out\")) out = " << gq(spec.name) << "\n";
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
    const std::string temporary = spec.name + ".tmp-plot-" + std::to_string(::getpid());
    const std::string cmd = "cd " + shq(dir.string()) + " && gnuplot -e " +
                            shq("out=" + gq(temporary)) + " " + shq(spec.name + ".gp") + " > " +
                            shq(log) + " 2>&1";
    const int status = std::system(cmd.c_str());
    const auto dropTemporaries = [&] {
        std::error_code ignored;
        for (const char* ext : {".png", ".svg"}) {
            std::filesystem::remove(dir / (temporary + ext), ignored);
        }
    };
    if (status != 0) {
        dropTemporaries();
        r.problem = "gnuplot failed on " + gp.string() + " (exit " +
                    std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + "; see " +
                    (dir / log).string() + ")";
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
    // rename is one step), named after this process.
    const std::filesystem::path dir =
        out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();
    const std::string stem =
        "." + out.filename().string() + ".tmp-plot-" + std::to_string(::getpid());
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
    const std::string cmd = "gnuplot -e " + shq("out=" + gq((dir / stem).string())) + " " +
                            shq(gp.string()) + " > " + shq(log.string()) + " 2>&1";
    const int status = std::system(cmd.c_str());
    if (status != 0 || !std::filesystem::exists(image)) {
        std::string why;
        std::ifstream in(log);
        std::getline(in, why);
        cleanUp();
        throw std::runtime_error("gnuplot failed drawing " + out.string() + " (exit " +
                                 std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                                 (why.empty() ? "" : ": " + why) + ")");
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
