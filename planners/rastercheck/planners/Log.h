#pragma once

#include <ompl/util/Console.h>

/** \file OMPL's console from inside namespace rastercheck, where OMPL's own macros (OMPL_INFORM,
    ...) would name rastercheck::ompl instead of ::ompl. */

/** \brief OMPL_LOG(INFO, "format", ...): OMPL's log at level LOG_<level>. */
#define OMPL_LOG(level, fmt, ...) ::ompl::msg::log(__FILE__, __LINE__, ::ompl::msg::LOG_##level, fmt, ##__VA_ARGS__)
