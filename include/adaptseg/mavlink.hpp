#pragma once
/// @file
/// Umbrella header of the mavlink component (CMake target adaptseg::mavlink; the C++ standard
/// library and POSIX only): a MAVLink 2 codec for the messages a companion computer exchanges
/// with a PX4 or ArduPilot autopilot, written from the MAVLink definitions (common.xml,
/// minimal.xml) and the mavlink.io serialization page, and the live link to the autopilot over
/// UDP or a serial device (VehicleLink; docs/mavlink.md).

#include <adaptseg/mavlink/camera_image_captured.hpp>
#include <adaptseg/mavlink/command_ack.hpp>
#include <adaptseg/mavlink/command_int.hpp>
#include <adaptseg/mavlink/command_long.hpp>
#include <adaptseg/mavlink/crc.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/extended_sys_state.hpp>
#include <adaptseg/mavlink/frame.hpp>
#include <adaptseg/mavlink/global_position_int.hpp>
#include <adaptseg/mavlink/gps_raw_int.hpp>
#include <adaptseg/mavlink/heartbeat.hpp>
#include <adaptseg/mavlink/home_position.hpp>
#include <adaptseg/mavlink/link_error.hpp>
#include <adaptseg/mavlink/link_options.hpp>
#include <adaptseg/mavlink/message.hpp>
#include <adaptseg/mavlink/message_type.hpp>
#include <adaptseg/mavlink/mission_current.hpp>
#include <adaptseg/mavlink/mission_item_reached.hpp>
#include <adaptseg/mavlink/open_transport.hpp>
#include <adaptseg/mavlink/parser.hpp>
#include <adaptseg/mavlink/position_target_global_int.hpp>
#include <adaptseg/mavlink/serial_transport.hpp>
#include <adaptseg/mavlink/set_position_target_global_int.hpp>
#include <adaptseg/mavlink/site_limits.hpp>
#include <adaptseg/mavlink/status_text.hpp>
#include <adaptseg/mavlink/sys_status.hpp>
#include <adaptseg/mavlink/transport.hpp>
#include <adaptseg/mavlink/udp_transport.hpp>
#include <adaptseg/mavlink/vehicle_link.hpp>
#include <adaptseg/mavlink/vehicle_mode.hpp>
#include <adaptseg/mavlink/vehicle_state.hpp>
