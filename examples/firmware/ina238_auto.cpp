// The talk's `ina238 auto`, as firmware would run it: open the parameter store over static
// memory and the generated tables, load the store file, and start one driver instance per
// INA238 instance of the device manifest (here: print what each would start with).
//
//   ina238_auto STORE_FILE [SAVE_TO]
//
// With SAVE_TO, the store is saved there through the C ABI (px4p_store_save) after loading.
// Built and run by tests/test_firmware.py; see docs/firmware.md for the build by hand.
#include <cstdio>
#include <cstdlib>

#include "px4_params.h"  // `px4params metadata --header`: structs, ids, px4params.hpp

extern "C" const px4p_tables px4_param_tables;  // `px4params metadata --firmware`

namespace {

// The store's memory, sized for the bundled manifest types (px4_param_tables says how much
// it needs; px4p_store_open refuses less).
px4p_slot slots[256];
uint8_t bytes[8192];
uint8_t file[8192];

// What `ina238 -X -b BUS -a ADDRESS start` gets on today's command line.
struct Cli {
    unsigned requested_bus;
    unsigned i2c_address;
    bool keep_running;
    uint16_t param;
};

int fail(const char *what, int code) {
    std::fprintf(stderr, "ina238_auto: %s: %s\n", what, px4p_error_name(code));
    return 1;
}

}  // namespace

int main(int argc, char **argv) {
    using namespace px4;
    if (argc < 2) {
        std::fprintf(stderr, "usage: ina238_auto STORE_FILE [SAVE_TO]\n");
        return 2;
    }
    int err = params::init(px4_param_tables, slots, sizeof slots / sizeof slots[0], bytes,
                           sizeof bytes);
    if (err < 0) {
        return fail("opening the store", err);
    }
    FILE *in = std::fopen(argv[1], "rb");
    if (in == nullptr) {
        std::perror(argv[1]);
        return 1;
    }
    const size_t len = std::fread(file, 1, sizeof file, in);
    std::fclose(in);
    err = px4p_store_load(&params::store(), file, len);
    if (err < 0) {
        return fail("loading the store file", err);
    }

    std::printf("ina238 auto\n");
    for (auto config : params::param_find_instances(params::INA238)) {
        if (config.bus.union_tag != 0) {  // the INA238 driver is I2C only
            std::printf("  INA238#%u not on I2C: not started\n", config.instance);
            continue;
        }
        Cli cli{};
        cli.i2c_address = config.bus.i2c.address;
        cli.requested_bus = config.bus.i2c.bus_id;
        cli.keep_running = true;
        cli.param = config.instance;
        std::printf("  INA238#%u I2C bus %u address 0x%02X current=%u shunt=%.5g\n", cli.param,
                    cli.requested_bus, cli.i2c_address, static_cast<unsigned>(config.current),
                    static_cast<double>(config.shunt));
    }

    if (argc > 2) {
        const int size = px4p_store_save(&params::store(), file, sizeof file);
        if (size < 0) {
            return fail("saving the store", size);
        }
        FILE *out = std::fopen(argv[2], "wb");
        if (out == nullptr || std::fwrite(file, 1, static_cast<size_t>(size), out) != static_cast<size_t>(size)) {
            std::perror(argv[2]);
            return 1;
        }
        std::fclose(out);
    }
    return 0;
}
