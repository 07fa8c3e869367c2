/* The C ABI's answers to good and bad calls, printed one per line for tests/test_firmware.py
 * to compare with what docs/firmware.md promises. Built with the generated tables. */
#include <stdio.h>
#include <string.h>

#include "px4_params.h"
#include "px4params.h"

extern const px4p_tables px4_param_tables;

static px4p_store store;
static px4p_store never_opened;
static px4p_slot slots[256];
static uint8_t bytes[8192];

static void show(const char *what, int32_t result) {
    printf("%s: %d %s\n", what, (int)result, px4p_error_name(result));
}

int main(void) {
    uint8_t buf[4096];
    px4p_value v;
    const uint32_t ina = PX4_PARAM_INA238;

    show("get from a store never opened", px4p_get(&never_opened, ina, 0, 0, buf, sizeof buf));
    show("open without tables", px4p_store_open(&store, NULL, slots, 256, bytes, sizeof bytes));
    show("open with too little memory", px4p_store_open(&store, &px4_param_tables, slots, 256, bytes, 16));
    show("open", px4p_store_open(&store, &px4_param_tables, slots, 256, bytes, sizeof bytes));
    show("get an absent instance", px4p_get(&store, ina, 0, 0, buf, sizeof buf));
    show("add the lowest free", px4p_add(&store, ina, -1));
    show("add #2", px4p_add(&store, ina, 2));
    show("add #2 again", px4p_add(&store, ina, 2));
    show("add #9", px4p_add(&store, ina, 9));
    show("add the lowest free", px4p_add(&store, ina, -1));
    show("add the lowest free", px4p_add(&store, ina, -1));
    show("add the lowest free", px4p_add(&store, ina, -1));
    show("add to no such parameter", px4p_add(&store, PX4_PARAM_COUNT, -1));
    show("get into 1 byte", px4p_get(&store, ina, 0, 0, buf, 1));
    int32_t len = px4p_get(&store, ina, 0, 0, buf, sizeof buf);
    show("get", len);
    show("set the same bytes", px4p_set(&store, ina, 0, 0, buf, (size_t)len));
    show("set one byte short", px4p_set(&store, ina, 0, 0, buf, (size_t)len - 1));
    show("get leaf [5] (current)", px4p_get_leaf(&store, ina, 0, 0, 5, &v));
    printf("  value kind %u: %llu\n", v.kind, (unsigned long long)v.u);
    v.kind = PX4P_VALUE_UINT;
    v.u = 200;
    show("set leaf [5] to 200", px4p_set_leaf(&store, ina, 1, 0, 5, &v, 0));
    px4p_get_leaf(&store, ina, 1, 0, 5, &v);
    printf("  read back: %llu\n", (unsigned long long)v.u);
    v.u = 5000;
    show("set leaf [5] to 5000", px4p_set_leaf(&store, ina, 1, 0, 5, &v, 0));
    show("set leaf [5] to 5000, saturated", px4p_set_leaf(&store, ina, 1, 0, 5, &v, 1));
    px4p_get_leaf(&store, ina, 1, 0, 5, &v);
    printf("  read back: %llu\n", (unsigned long long)v.u);
    show("set leaf [0] (p_version)", px4p_set_leaf(&store, ina, 1, 0, 0, &v, 0));
    show("get leaf [99]", px4p_get_leaf(&store, ina, 1, 0, 99, &v));
    show("remove #2", px4p_remove(&store, ina, 2));
    show("remove #2 again", px4p_remove(&store, ina, 2));
    printf("instances:");
    for (int32_t i = px4p_next_instance(&store, ina, -1); i >= 0; i = px4p_next_instance(&store, ina, i)) {
        printf(" %d", (int)i);
    }
    printf("\n");
    show("save into 8 bytes", px4p_store_save(&store, buf, 8));
    len = px4p_store_save(&store, buf, sizeof buf);
    show("save", len);
    show("load it back", px4p_store_load(&store, buf, (size_t)len));
    buf[len - 1] ^= 0x80;
    show("load with a flipped bit", px4p_store_load(&store, buf, (size_t)len));
    show("load nothing", px4p_store_load(&store, buf, 0));
    show("load from NULL", px4p_store_load(&store, NULL, 5));
    show("name of -99", -99);
    return 0;
}
