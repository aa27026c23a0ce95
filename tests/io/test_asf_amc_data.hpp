// A small valid ASF/AMC pair: a root and two leg bones with limits, an axis and dofs (ASF, in
// the file's 0.45 inch unit and degrees), and two frames giving the bones in another order
// (AMC). The base of test_asf_amc.cpp's malformed-input table and the AMC fuzz harness's
// skeleton (tests/fuzz).
#pragma once

#include <string>

namespace kg::test {

inline const std::string kTinyAsf =
    "# a tiny figure\n"
    ":version 1.10\n"
    ":name tiny\n"
    ":units\n"
    "  mass 1.0\n"
    "  length 0.45\n"
    "  angle deg\n"
    ":documentation\n"
    "   two bones\n"
    ":root\n"
    "   order TX TY TZ RX RY RZ\n"
    "   axis XYZ\n"
    "   position 0 0 0\n"
    "   orientation 0 0 0\n"
    ":bonedata\n"
    "  begin\n"
    "     id 1\n"
    "     name lfemur\n"
    "     direction 0 -1 0\n"
    "     length 7\n"
    "     axis 0 0 20 XYZ\n"
    "    dof rx ry rz\n"
    "    limits (-160.0 20.0)\n"
    "           (-70.0 70.0)\n"
    "           (-60.0 70.0)\n"
    "  end\n"
    "  begin\n"
    "     id 2\n"
    "     name ltibia\n"
    "     direction 0 -1 0\n"
    "     length 7\n"
    "     axis 0 0 20 XYZ\n"
    "    dof rx\n"
    "    limits (-10.0 170.0)\n"
    "  end\n"
    ":hierarchy\n"
    "  begin\n"
    "    root lfemur\n"
    "    lfemur ltibia\n"
    "  end\n";

inline const std::string kTinyAmc =
    "#!OML:ASF tiny.asf\n"
    ":FULLY-SPECIFIED\n"
    ":DEGREES\n"
    "1\n"
    "root 0 17 0 0 0 0\n"
    "lfemur 10 0 0\n"
    "ltibia 20\n"
    "2\n"
    "ltibia 21\n"
    "root 0 17 0 1 2 3\n"
    "lfemur 11 0 0\n";

}  // namespace kg::test
