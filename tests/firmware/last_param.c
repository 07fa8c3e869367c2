/* The C ABI at the end of the generated tables: the last parameter in ID order
 * (PX4_PARAM_COUNT - 1) opens, adds, reads and saves like any other; PX4_PARAM_COUNT, one
 * beyond the table, is refused. Prints one line per call for tests/test_planted_firmware.py;
 * writes the saved store file to argv[1]. */
#include <stdio.h>

#include "px4_params.h"
#include "px4params.h"

extern const px4p_tables px4_param_tables;

static px4p_store store;
static px4p_slot slots[256];
static uint8_t bytes[8192];

static void show(const char *what, int32_t result) {
    printf("%s: %d %s\n", what, (int)result, px4p_error_name(result));
}

int main(int argc, char **argv) {
    uint8_t buf[4096];
    px4p_value v;
    const uint32_t last = PX4_PARAM_COUNT - 1;
    if (argc != 2) {
        fprintf(stderr, "usage: last_param FILE\n");
        return 2;
    }
    show("open", px4p_store_open(&store, &px4_param_tables, slots, 256, bytes, sizeof bytes));
    show("add the last parameter", px4p_add(&store, last, -1));
    for (uint32_t which = 0; which < 2; which++) {
        for (uint32_t leaf = 0; leaf < 6; leaf++) {
            int32_t r = px4p_get_leaf(&store, last, 0, (uint8_t)which, leaf, &v);
            printf("%s [%u]: %s kind %u: %llu\n", which ? "default" : "value", (unsigned)leaf,
                   px4p_error_name(r), v.kind, (unsigned long long)v.u);
        }
    }
    show("add beyond the table", px4p_add(&store, PX4_PARAM_COUNT, -1));
    show("get beyond the table", px4p_get(&store, PX4_PARAM_COUNT, 0, 0, buf, sizeof buf));
    show("get a leaf beyond the table", px4p_get_leaf(&store, PX4_PARAM_COUNT, 0, 0, 0, &v));
    show("instances beyond the table", px4p_next_instance(&store, PX4_PARAM_COUNT, -1));
    int32_t len = px4p_store_save(&store, buf, sizeof buf);
    show("save", len > 0 ? 0 : len);
    FILE *f = fopen(argv[1], "wb");
    if (f == NULL || len <= 0 || fwrite(buf, 1, (size_t)len, f) != (size_t)len || fclose(f) != 0) {
        fprintf(stderr, "cannot write %s\n", argv[1]);
        return 1;
    }
    return 0;
}
