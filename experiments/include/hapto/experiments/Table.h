#pragma once
/// One table of results written as CSV, JSON and markdown from a single column list.
///
/// Design note. Every experiment reports rows of figures in three forms: a CSV for scripts, a
/// JSON array for tools, and a markdown table for people. Each column is declared once (its
/// name, the CSV header and JSON key; its unit; how markdown shows it), so the three forms
/// cannot disagree on names, order or units. Cells are typed: numbers stay numbers in JSON,
/// flags are 1/0 in CSV and true/false in JSON.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace hapto::experiments {

/// Where a column appears.
enum class ColumnIn : std::uint8_t {
    All,      ///< CSV, JSON and markdown.
    Data,     ///< CSV and JSON only (too detailed for the markdown table).
    Markdown, ///< Markdown only (a summary cell composed for people).
};

/// One column: declared once, used by all three forms.
struct Column {
    /// A column; only the name is required.
    Column(std::string name, std::string unit = {}, int decimals = -1, std::string heading = {},
           ColumnIn in = ColumnIn::All)
        : name(std::move(name)), unit(std::move(unit)), decimals(decimals),
          heading(std::move(heading)), in(in) {}

    std::string name;    ///< CSV header and JSON key, snake_case with its unit (load_p50_pct).
    std::string unit;    ///< Unit ("%", "Hz", "ns", ...), or empty for counts and text.
    int decimals;        ///< Markdown: fixed places for numbers; -1: as in CSV (%.6g).
    std::string heading; ///< Markdown heading; empty: the name, then the unit in brackets.
    ColumnIn in;         ///< Which forms show it.
};

/// One cell: text, a number, a whole number or a flag.
using Cell = std::variant<std::string, double, std::int64_t, bool>;

/// Rows of cells under a fixed column list. [control]
class Table {
public:
    /// The columns, in order. Throws std::logic_error on an empty or repeated name.
    explicit Table(std::vector<Column> columns);

    /// Appends a row with one cell per column. Throws std::logic_error otherwise.
    void add(std::vector<Cell> row);

    /// The columns, in order.
    const std::vector<Column>& columns() const { return mColumns; }
    /// The rows added, in order, one cell per column.
    const std::vector<std::vector<Cell>>& rows() const { return mRows; }
    /// The number of rows.
    std::size_t size() const { return mRows.size(); }
    /// The index of a column by name; throws std::logic_error when there is none.
    std::size_t column(const std::string& name) const;

    /// CSV: a header of names, then the rows; numbers as %.6g, flags 1/0, fields holding a
    /// comma, quote or line break quoted (RFC 4180). Markdown-only columns are left out.
    std::string csv() const;
    /// JSON: an array of objects keyed by name, in column order; numbers as numbers, flags as
    /// booleans. Markdown-only columns are left out.
    nlohmann::ordered_json json() const;
    /// One row as a JSON object (as in json()).
    nlohmann::ordered_json json(std::size_t row) const;
    /// Markdown: a padded table of the columns shown there, under their headings; numbers
    /// with the column's decimals, flags yes/no, '|' in text escaped.
    std::string markdown() const;
    /// Markdown of only the rows for which `keep(row index)` is true.
    template <class Keep> std::string markdown(Keep keep) const {
        std::vector<std::size_t> rows;
        for (std::size_t i = 0; i < mRows.size(); ++i) {
            if (keep(i)) {
                rows.push_back(i);
            }
        }
        return markdownOf(rows);
    }

    /// Writes csv() to `path`, whole or not at all. Throws like writeFileAtomically.
    void writeCsv(const std::filesystem::path& path) const;

private:
    std::string markdownOf(const std::vector<std::size_t>& rows) const;

    std::vector<Column> mColumns;
    std::vector<std::vector<Cell>> mRows;
};

/// A field quoted for CSV when it holds a comma, a quote or a line break. [any thread]
std::string csvField(const std::string& text);
/// A number as CSV writes it: %.6g. [any thread]
std::string csvNumber(double value);

} // namespace hapto::experiments
