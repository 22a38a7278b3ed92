#pragma once
// Private: the packet walk of the IG rays (IgPacketWalk), in its parts: the lanes' state and
// the walk's declaration (ig_packet_walk.hpp, which says how the walk works), rays entering
// the lanes (ig_packet_enter.hpp), the packet steps (ig_packet_step.hpp) and rays ending
// (ig_packet_end.hpp). Included by one source per lane width, after ig_rays_impl.hpp and
// inside that source's target options.

#include "ig_packet_walk.hpp"
#include "ig_packet_enter.hpp"
#include "ig_packet_step.hpp"
#include "ig_packet_end.hpp"

#undef NBV_PACKET_WALK_FIELDS
#undef NBV_WALK_NONE
