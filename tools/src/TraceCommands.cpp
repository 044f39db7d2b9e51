// `hapto trace export|info`: look inside trace files written by `hapto run --record`.

#include "Commands.h"

#include "hapto/devices/TraceReader.h"
#include "hapto/scenes/InputError.h"
#include "hapto/scenes/OutputFile.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>

namespace hapto::cli {
namespace {

void appendNumber(std::string& out, double v) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, res.ptr);
}

// Writes the CSV: one header row, one row per sample; numbers round-trip exactly.
void exportCsv(const std::string& tracePath, const std::string& outPath) {
    const bool toFile = !outPath.empty() && outPath != "-";
    if (toFile) {
        refuseSameFile(outPath, "-o", tracePath, "the trace");
        checkOutputFile(outPath, "-o");
    }
    TraceReader reader(tracePath);
    std::unique_ptr<AtomicOutputFile> file;
    std::ostream* os = &std::cout;
    if (toFile) {
        file = std::make_unique<AtomicOutputFile>(outPath);
        os = &file->stream();
    }
    std::string out = "tick,time_ns,x_m,y_m,z_m,fx_n,fy_n,fz_n,compute_ns,io_ns,status,buttons\n";
    TraceSample s;
    std::uint64_t rows = 0;
    while (reader.next(s)) {
        out += std::to_string(s.tick);
        out += ',';
        out += std::to_string(s.timeNs);
        for (int i = 0; i < 3; ++i) {
            out += ',';
            appendNumber(out, s.positionM[i]);
        }
        for (int i = 0; i < 3; ++i) {
            out += ',';
            appendNumber(out, s.forceN[i]);
        }
        out += ',';
        out += std::to_string(s.computeNs);
        out += ',';
        out += std::to_string(s.ioNs);
        out += ',';
        out += statusName(s.status);
        out += ',';
        out += std::to_string(s.buttons);
        out += '\n';
        ++rows;
        if (out.size() > (1u << 20)) {
            os->write(out.data(), static_cast<std::streamsize>(out.size()));
            out.clear();
        }
    }
    os->write(out.data(), static_cast<std::streamsize>(out.size()));
    os->flush();
    if (!*os) {
        throw std::runtime_error((outPath.empty() ? std::string("stdout") : outPath) +
                                 ": write failed (disk full?)");
    }
    if (file) {
        file->commit();
        std::cerr << "wrote " << rows << " samples to " << outPath << "\n";
    }
}

void printInfo(const std::string& tracePath) {
    TraceReader reader(tracePath);
    const TraceHeader& h = reader.header();
    std::uint64_t first = 0, last = 0, notOk = 0, gaps = 0, n = 0;
    double maxForce = 0.0;
    TraceSample s;
    while (reader.next(s)) {
        if (n == 0) {
            first = s.tick;
        } else if (s.tick != last + 1) {
            gaps += s.tick - last - 1;
        }
        last = s.tick;
        notOk += s.status != DeviceStatus::Ok;
        maxForce = std::max(maxForce, glm::length(s.forceN));
        ++n;
    }
    std::printf("trace:    %s\n", tracePath.c_str());
    std::printf("device:   %s (%s)\n", h.name.c_str(), h.kind.c_str());
    std::printf("rate:     %g Hz\n", h.rateHz);
    std::printf("samples:  %llu%s\n", static_cast<unsigned long long>(n),
                h.finished ? "" : " (recording was not closed)");
    if (n > 0) {
        std::printf("ticks:    %llu .. %llu, %llu not recorded\n",
                    static_cast<unsigned long long>(first), static_cast<unsigned long long>(last),
                    static_cast<unsigned long long>(gaps));
        std::printf("not ok:   %llu reads\n", static_cast<unsigned long long>(notOk));
        std::printf("max |F|:  %.4f N\n", maxForce);
    }
}

} // namespace

void addTraceCommands(CLI::App& app) {
    CLI::App* trace =
        app.add_subcommand("trace", "Look inside trace files written by `hapto run --record`");
    trace->require_subcommand(1);
    {
        auto* cmd = trace->add_subcommand(
            "export", "Write a trace as CSV: tick, time_ns, position (m, device frame), force "
                      "(N), compute_ns, io_ns, status, buttons");
        auto path = std::make_shared<std::string>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("trace", *path, "The trace file")->required();
        cmd->add_option("-o,--output", *out, "CSV file to write (default: standard output)");
        cmd->callback([path, out] { exportCsv(*path, *out); });
    }
    {
        auto* cmd = trace->add_subcommand("info", "Describe a trace: device, rate, samples");
        auto path = std::make_shared<std::string>();
        cmd->add_option("trace", *path, "The trace file")->required();
        cmd->callback([path] { printInfo(*path); });
    }
}

} // namespace hapto::cli
