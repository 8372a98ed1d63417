#include "csp/dynamics/workspace.hpp"
