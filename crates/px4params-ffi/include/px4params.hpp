/*
 * px4params.hpp: the "PX4 Device Manifest" talk's C++ API, header-only, over the C ABI
 * (px4params.h) and the structs of the header `px4params metadata --header` writes, which
 * includes this file and adds each type's codec<T> and each parameter's typed id
 * (px4::params::INA238).
 *
 *   px4::params::init(px4_param_tables, slots, slot_count, bytes, byte_count);
 *   px4p_store_load(&px4::params::store(), file, file_len);
 *
 *   px_Ina238 data;
 *   load_and_decode_param<px_Ina238>(px4::params::INA238, 0, data);
 *   data.current = 100;
 *   store_and_encode_param<px_Ina238>(px4::params::INA238, 0, data);
 *
 *   for (auto config : param_find_instances(params::INA238)) {  // the driver's `auto` start
 *       cli.i2c_address = config.bus.i2c.address;
 *       cli.requested_bus = config.bus.i2c.bus_id;
 *       ...
 *   }
 *
 * Functions return 0 (or a count) on success and a negative PX4P_ERR_* code on failure;
 * px4p_error_name() names it.
 */
#ifndef PX4PARAMS_HPP
#define PX4PARAMS_HPP

#include <cstddef>
#include <cstdint>

#include "px4params.h"

namespace px4 {
namespace params {

/// How a generated struct is encoded and decoded (specialized by the metadata header).
template <typename T>
struct codec;

/// A parameter's id with its type: px4::params::INA238 is a param<px_Ina238>.
template <typename T>
struct param {
    uint32_t id;
};

/// The firmware's one parameter store.
inline px4p_store &store() {
    static px4p_store the_store;
    return the_store;
}

/// Opens store() over the generated tables and memory of (at least) the sizes they give.
inline int init(const px4p_tables &tables, px4p_slot *slots, size_t slot_count, uint8_t *bytes,
                size_t byte_count) {
    return px4p_store_open(&store(), &tables, slots, slot_count, bytes, byte_count);
}

/// Reads instance `instance` of parameter `p` into `out`.
template <typename T>
int load_and_decode_param(param<T> p, uint16_t instance, T &out) {
    uint8_t buffer[codec<T>::max_size];
    const int32_t len = px4p_get(&store(), p.id, instance, 0, buffer, sizeof buffer);
    if (len < 0) {
        return len;
    }
    return codec<T>::decode(buffer, static_cast<size_t>(len), out) < 0 ? PX4P_ERR_VALUE : 0;
}

/// Writes `value` as instance `instance` of parameter `p` (which must exist: px4p_add).
template <typename T>
int store_and_encode_param(param<T> p, uint16_t instance, const T &value) {
    uint8_t buffer[codec<T>::max_size];
    const int len = codec<T>::encode(value, buffer);
    if (len < 0) {
        return PX4P_ERR_VALUE;
    }
    return px4p_set(&store(), p.id, instance, 0, buffer, static_cast<size_t>(len));
}

/// One instance as param_find_instances() yields it: its value, and which instance it is.
template <typename T>
struct instance_config : T {
    param<T> parameter;
    uint16_t instance;
};

/// The present instances of a parameter, each loaded and decoded as it is reached.
template <typename T>
class instances {
public:
    class iterator {
    public:
        iterator(param<T> p, int32_t at) : p_(p), at_(at) { load(); }
        const instance_config<T> &operator*() const { return config_; }
        iterator &operator++() {
            at_ = px4p_next_instance(&store(), p_.id, at_);
            load();
            return *this;
        }
        bool operator!=(const iterator &other) const { return at_ != other.at_; }

    private:
        void load() {
            // An instance that does not decode (it cannot: the store checks every value) ends
            // the walk rather than yielding garbage.
            while (at_ >= 0) {
                config_.parameter = p_;
                config_.instance = static_cast<uint16_t>(at_);
                if (load_and_decode_param<T>(p_, config_.instance, config_) == 0) {
                    return;
                }
                at_ = px4p_next_instance(&store(), p_.id, at_);
            }
            at_ = PX4P_ERR_END;
        }
        param<T> p_;
        int32_t at_;
        instance_config<T> config_{};
    };

    explicit instances(param<T> p) : p_(p) {}
    iterator begin() const { return iterator(p_, px4p_next_instance(&store(), p_.id, -1)); }
    iterator end() const { return iterator(p_, PX4P_ERR_END); }

private:
    param<T> p_;
};

/// The present instances of `p`, for a driver's autostart loop.
template <typename T>
instances<T> param_find_instances(param<T> p) {
    return instances<T>(p);
}

}  // namespace params
}  // namespace px4

#endif /* PX4PARAMS_HPP */
