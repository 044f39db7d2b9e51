// The `hapto` command: one executable, one subcommand per task.

#include "Commands.h"
#include "Options.h"

#include "hapto/Version.h"
#include "hapto/io/InputError.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <string>

int main(int argc, char** argv) {
    CLI::App app{"hapto: a multi-device haptic runtime over one shared spatial index.\n"
                 "Units are SI throughout: metres, seconds, newtons, N/m.",
                 "hapto"};
    app.formatter(std::make_shared<hapto::cli::HelpFormatter>()); // inherited by every command
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Print help for every command, at every depth, and exit");
    app.set_version_flag("--version", std::string("hapto ") + hapto::kVersion,
                         "Print hapto's version and exit");

    hapto::cli::addSceneCommands(app);
    hapto::cli::addRunCommands(app);
    hapto::cli::addDeviceCommands(app);
    hapto::cli::addDemoCommands(app);
    hapto::cli::addBenchCommands(app);
    hapto::cli::addIndexCommands(app);
    hapto::cli::addRenderCommands(app);
    hapto::cli::addTraceCommands(app);
    hapto::cli::addReportCommands(app);
    hapto::cli::addExperimentCommands(app);
    hapto::cli::addSoakCommands(app);
    hapto::cli::addViewCommands(app);
    // After the commands: a footer set earlier would be inherited by each of them.
    hapto::cli::setExamples(
        &app, {"hapto run --duration 10 --view", "hapto demo grasp --view", "hapto scene info",
               "hapto scene grid --help   # one command; hapto --help-all: every command"});

    // A first word that is no option and no command is named as an unknown command (CLI11
    // would only say that an argument was not expected).
    if (argc > 1 && argv[1][0] != '-') {
        const std::string word = argv[1];
        bool known = false;
        const CLI::App& root = app;
        for (const CLI::App* sub : root.get_subcommands([](const CLI::App*) { return true; })) {
            known = known || sub->check_name(word);
        }
        if (!known) {
            std::cerr << "hapto: unknown command '" << word << "'; see hapto --help\n";
            return 2;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) { // --help, --help-all
            return app.exit(e);
        }
        std::cerr << "hapto: " << e.what() << "\n(run with --help for the options)\n";
        return 2;
    } catch (const hapto::InputError& e) {
        std::cerr << "hapto: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "hapto: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
