// vtloc: command-line front end of the engine. Exit status: 0 ok, 1 bad input
// or runtime error (one line "vtloc: ..." on stderr), 2 usage error. With
// VTLOC_VALIDATION=1 any validation-layer message is printed to stderr and
// makes the exit status 1.
#include <cstdio>
#include <cstring>
#include <string>

#include "apps/vtloc/cli.h"
#include "base/error.h"

using namespace vtloc;

namespace {

const char* kUsage =
    "usage: vtloc <command> [options]\n"
    "\n"
    "commands:\n"
    "  demo       run the shipped model on a shipped example; write a heat-map PNG and PLY\n"
    "  localize   localise one touch (tactile image + object mesh or point cloud)\n"
    "  sequence   several touches and the robot's motions between them: the sensor's pose on the object\n"
    "  shape      the gel's shape (indentation, contact) from one frame\n"
    "  calibrate  a GelSight calibration of your own from ball presses\n"
    "  info       a weight file's config, parameter count, size and tensors\n"
    "  devices    Vulkan devices and the limits the engine uses\n"
    "  check      cross-check the device against the CPU reference (model, or --ops: every op)\n"
    "  synth      build a synthetic GelSight dataset from meshes (docs/dataset.md)\n"
    "  eval       the paper's metrics for a model on a dataset (docs/eval.md)\n"
    "\n"
    "environment:\n"
    "  VTLOC_DEVICE=<index|name>   pick a device (default: discrete > integrated > CPU)\n"
    "  VTLOC_VALIDATION=1          Khronos validation layer on; any message fails the command\n"
    "  VTLOC_DATA_DIR=<dir>        where models/ and examples/ are, if not found by themselves\n"
    "\n"
    "`vtloc <command> --help` describes one command. Exit status: 0 ok, 1 bad input or\n"
    "runtime error, 2 usage error.\n";

using Command = int (*)(cli::Session&, int, char**);

Command find_command(const std::string& name) {
    if (name == "demo") return cli::cmd_demo;
    if (name == "localize" || name == "localise") return cli::cmd_localize;
    if (name == "sequence") return cli::cmd_sequence;
    if (name == "shape") return cli::cmd_shape;
    if (name == "calibrate") return cli::cmd_calibrate;
    if (name == "info") return cli::cmd_info;
    if (name == "devices") return cli::cmd_devices;
    if (name == "check") return cli::cmd_check;
    if (name == "synth") return cli::cmd_synth;
    if (name == "eval") return cli::cmd_eval;
    return nullptr;
}

// Prints what the validation layer said; true if it said anything.
bool report_validation(cli::Session& s) {
    if (!s.context || !s.context->validation_enabled()) return false;
    std::vector<std::string> msgs = s.context->take_validation_messages();
    for (const std::string& m : msgs) std::fprintf(stderr, "vtloc: validation layer: %s\n", m.c_str());
    return !msgs.empty();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
        std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    const std::string name = argv[1];
    Command cmd = find_command(name);
    if (!cmd) {
        std::fprintf(stderr, "vtloc: unknown command '%s' (see 'vtloc --help')\n", name.c_str());
        return 2;
    }
    cli::Session session;
    int rc = 1;
    try {
        rc = cmd(session, argc, argv);
    } catch (const cli::UsageError& e) {
        std::fprintf(stderr, "vtloc %s: %s (see 'vtloc %s --help')\n", name.c_str(), e.what(), name.c_str());
        rc = 2;
    } catch (const api::Error& e) {
        std::fprintf(stderr, "vtloc: %s\n", e.what());
        rc = 1;
    } catch (const vtloc::Error& e) {  // the engine's own layers' user-facing errors (a touches file, ...)
        std::fprintf(stderr, "vtloc: %s\n", e.what());
        rc = 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vtloc: internal error: %s\n", e.what());
        rc = 1;
    }
    if (report_validation(session) && rc == 0) rc = 1;
    return rc;
}
