// SPDX-License-Identifier: GPL-3.0-or-later
// The extrapolated bounce tail shared by the LPV gather and the VCT bounces (common/bounce_tail.py says why):
// the light of bounces K+1 … N is the last gathered increment times u_tail = Σ_{j=1}^{N−K} r^j per channel.
#pragma once

vec3 bounce_tail(vec3 total, vec3 increment, vec3 tail) {
    return total + increment * tail;
}
