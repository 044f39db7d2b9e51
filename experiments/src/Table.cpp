// One table of results, three forms (CSV, JSON, markdown), one column list.

#include "hapto/experiments/Table.h"

#include "hapto/experiments/ExperimentSupport.h"

#include "hapto/io/OutputFile.h"

#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>

namespace hapto::experiments {

std::string csvField(const std::string& text) {
    if (text.find_first_of(",\"\n\r") == std::string::npos) {
        return text;
    }
    std::string q = "\"";
    for (const char c : text) {
        q += c == '"' ? std::string("\"\"") : std::string(1, c);
    }
    return q + "\"";
}

std::string csvNumber(double value) {
    char text[48];
    std::snprintf(text, sizeof text, "%.6g", value);
    return text;
}

Table::Table(std::vector<Column> columns) : mColumns(std::move(columns)) {
    if (mColumns.empty()) {
        throw std::logic_error("Table: no columns");
    }
    std::set<std::string> names;
    for (const Column& c : mColumns) {
        if (c.name.empty() || !names.insert(c.name).second) {
            throw std::logic_error("Table: empty or repeated column name '" + c.name + "'");
        }
    }
}

void Table::add(std::vector<Cell> row) {
    if (row.size() != mColumns.size()) {
        throw std::logic_error("Table: a row of " + std::to_string(row.size()) + " cells for " +
                               std::to_string(mColumns.size()) + " columns");
    }
    mRows.push_back(std::move(row));
}

std::size_t Table::column(const std::string& name) const {
    for (std::size_t i = 0; i < mColumns.size(); ++i) {
        if (mColumns[i].name == name) {
            return i;
        }
    }
    throw std::logic_error("Table: no column '" + name + "'");
}

namespace {

std::string csvCell(const Cell& cell) {
    struct {
        std::string operator()(const std::string& s) const { return csvField(s); }
        std::string operator()(double v) const { return csvNumber(v); }
        std::string operator()(std::int64_t v) const { return std::to_string(v); }
        std::string operator()(bool v) const { return v ? "1" : "0"; }
    } visit;
    return std::visit(visit, cell);
}

nlohmann::ordered_json jsonCell(const Cell& cell) {
    return std::visit([](const auto& v) { return nlohmann::ordered_json(v); }, cell);
}

std::string markdownCell(const Cell& cell, int decimals) {
    if (const auto* s = std::get_if<std::string>(&cell)) {
        std::string out;
        for (const char c : *s) {
            out += c == '|' ? std::string("\\|") : std::string(1, c);
        }
        return out;
    }
    if (const auto* v = std::get_if<double>(&cell)) {
        return decimals >= 0 ? fmt(*v, decimals) : csvNumber(*v);
    }
    if (const auto* v = std::get_if<std::int64_t>(&cell)) {
        return std::to_string(*v);
    }
    return std::get<bool>(cell) ? "yes" : "no";
}

} // namespace

std::string Table::csv() const {
    std::ostringstream out;
    bool first = true;
    for (const Column& c : mColumns) {
        if (c.in != ColumnIn::Markdown) {
            out << (first ? "" : ",") << csvField(c.name);
            first = false;
        }
    }
    out << "\n";
    for (const auto& row : mRows) {
        first = true;
        for (std::size_t i = 0; i < mColumns.size(); ++i) {
            if (mColumns[i].in != ColumnIn::Markdown) {
                out << (first ? "" : ",") << csvCell(row[i]);
                first = false;
            }
        }
        out << "\n";
    }
    return out.str();
}

nlohmann::ordered_json Table::json(std::size_t row) const {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    for (std::size_t i = 0; i < mColumns.size(); ++i) {
        if (mColumns[i].in != ColumnIn::Markdown) {
            j[mColumns[i].name] = jsonCell(mRows.at(row)[i]);
        }
    }
    return j;
}

nlohmann::ordered_json Table::json() const {
    nlohmann::ordered_json j = nlohmann::ordered_json::array();
    for (std::size_t r = 0; r < mRows.size(); ++r) {
        j.push_back(json(r));
    }
    return j;
}

std::string Table::markdown() const {
    return markdown([](std::size_t) { return true; });
}

std::string Table::markdownOf(const std::vector<std::size_t>& rows) const {
    std::vector<std::string> header;
    std::vector<std::size_t> shown;
    for (std::size_t i = 0; i < mColumns.size(); ++i) {
        const Column& c = mColumns[i];
        if (c.in == ColumnIn::Data) {
            continue;
        }
        shown.push_back(i);
        header.push_back(!c.heading.empty() ? c.heading
                         : c.unit.empty()   ? c.name
                                            : c.name + " (" + c.unit + ")");
    }
    std::vector<std::vector<std::string>> cells;
    for (const std::size_t r : rows) {
        std::vector<std::string> line;
        for (const std::size_t i : shown) {
            line.push_back(markdownCell(mRows[r][i], mColumns[i].decimals));
        }
        cells.push_back(std::move(line));
    }
    return markdownTable(header, cells);
}

void Table::writeCsv(const std::filesystem::path& path) const {
    writeFileAtomically(path, csv());
}

} // namespace hapto::experiments
