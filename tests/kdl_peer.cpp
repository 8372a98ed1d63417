#include "kdl_peer.hpp"
