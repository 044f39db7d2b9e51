#pragma once
/// Line plots through gnuplot (PNG via pngcairo and SVG), from generated scripts.

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hapto::experiments {

/// One line of a panel: (x, y) points in the order drawn.
struct PlotSeries {
    std::string title;                             ///< Legend text.
    std::vector<std::pair<double, double>> points; ///< (x, y) in the panel's units.
    /// Per point: drawn with the panel's unstable mark as well (empty: none is).
    std::vector<bool> unstable;
    bool dashed = false;    ///< A dashed line (e.g. p50 beside the solid p99.9).
    int style = -1;         ///< Colour and point type (1, 2, ...); -1: the series' position + 1.
    bool linesOnly = false; ///< A plain line, no point marks (a time series of many points).
    /// Per point: the (low, high) ends of an error bar in y (e.g. a 95 % interval across
    /// repeats); empty: no bars. Shorter than `points`: the rest have none.
    std::vector<std::pair<double, double>> errors{};
    /// Points (with their error bars) not joined by lines: for categorical x (device names) or
    /// cells that are not a curve.
    bool pointsOnly = false;
    /// gnuplot dash type (1 solid, 2 dashed, 3 dotted, 4 dash-dot, 5 dash-dot-dot); 0: from
    /// `dashed`. Tells the lines of one colour apart (a device's x, y and z).
    int dash = 0;
};

/// The colour of a series or span style 1, 2, ...: ten distinct colours (matplotlib's "tab10",
/// Vega's category10), cycling; no two neighbours are shades of one hue. [any thread]
std::string plotColour(int style);

/// One set of axes.
struct PlotPanel {
    std::string title;              ///< Above the panel.
    std::string xLabel;             ///< The x axis's label, with its unit.
    std::string yLabel;             ///< The y axis's label, with its unit.
    bool logX = false;              ///< Log x scale (non-positive values are dropped).
    bool logY = false;              ///< Log y scale (non-positive values are dropped).
    std::vector<PlotSeries> series; ///< The lines.
    std::optional<double> limitY;   ///< A dashed horizontal line (e.g. 100 % load).
    std::string limitTitle;         ///< Its legend text.
    std::vector<double> xTics;      ///< A labelled tic at each of these x (empty: gnuplot's).
    std::vector<std::string> xTicLabels{}; ///< Text for each of xTics (empty: the numbers).
    /// Shaded x intervals [from, to] behind the lines (e.g. when a device was in contact).
    std::vector<std::pair<double, double>> spans{};
    std::string spanTitle{}; ///< Legend text of the shading (empty: none).
    /// Per span: its style (colour by plotColour, translucent); empty: every span grey under
    /// `spanTitle`. Spans of several devices then overlap visibly.
    std::vector<int> spanStyles{};
    /// With spanStyles: the key text of style s at [s - 1] (e.g. "hand0 in contact").
    std::vector<std::string> spanStyleTitles{};
};

/// An empty panel with its title and axis labels (units in the labels).
inline PlotPanel panel(std::string title, std::string xLabel, std::string yLabel) {
    PlotPanel p;
    p.title = std::move(title);
    p.xLabel = std::move(xLabel);
    p.yLabel = std::move(yLabel);
    return p;
}

/// A figure: panels side by side, or in a grid of `columns` columns.
struct PlotSpec {
    std::string name;              ///< File stem: NAME.gp, NAME.png, NAME.svg.
    std::string title;             ///< Figure title.
    std::vector<PlotPanel> panels; ///< The figure's panels, in layout order.
    int panelWidthPx = 520;        ///< Width of one panel (px).
    int heightPx = 420;            ///< Height (px).
    bool shareY = false;           ///< One y range for every panel (panels of the same quantity).
    std::string unstableTitle = "unstable"; ///< Key text of the unstable mark.
    int columns = 0; ///< Panels per row (0: all in one row); the image grows by rows.
    bool png = true; ///< Draw NAME.png.
    bool svg = true; ///< Draw NAME.svg.
    /// A line under the title (e.g. "5 runs of 0.5 s per cell; bars: 95 % interval"); empty: none.
    std::string caption{};
};

/// What drawPlot made.
struct PlotResult {
    std::vector<std::filesystem::path> files; ///< The PNG and SVG written (empty on failure).
    std::string problem; ///< Why nothing was drawn ("gnuplot not found", ...), else empty.
};

/// The y range every panel of a shared-y figure uses, data and limit lines included (log
/// panels: positive values only), widened a little; nullopt when there is no data. [any thread]
std::optional<std::pair<double, double>> sharedYRange(const PlotSpec& spec);

/// The gnuplot script drawPlot runs: data inline, a PNG then an SVG of the panels. Every text
/// (titles, labels, names) is a string constant with every special byte escaped, so no name or
/// path can run as gnuplot code or a shell command. [any thread]
std::string plotScript(const PlotSpec& spec);

/// True when a `gnuplot` executable is on PATH. [control]
bool gnuplotAvailable();

/// Writes DIR/NAME.gp (data inline) and runs gnuplot on it (directly, no shell, in DIR) to make
/// DIR/NAME.png and DIR/NAME.svg. Never throws for a missing or failing gnuplot: says so in
/// `problem`. [control]
PlotResult drawPlot(const std::filesystem::path& dir, const PlotSpec& spec);

/// Draws one image, `out` (PNG or SVG by its extension, ".png" or ".svg"), through a temporary
/// beside it renamed into place when whole, so `out` is either as before or complete; the
/// script goes to `script` (atomically) when not empty, else to a temporary removed after.
/// Throws InputError for an extension other than .png or .svg, std::runtime_error when gnuplot
/// is missing or fails (naming its log). [control]
void drawPlotFile(const PlotSpec& spec, const std::filesystem::path& out,
                  const std::filesystem::path& script = {});

} // namespace hapto::experiments
