# SPDX-License-Identifier: MIT
# Create (and optionally compile) the torqueloop Quartus project without Python:
#
#   quartus_sh -t constraints/create_project.tcl            ;# project only
#   quartus_sh -t constraints/create_project.tcl compile    ;# project + full compile
#
# Run from anywhere; the project goes to build/quartus/ of this repository
# (de0_cv_top.qpf + a copy of constraints/de0_cv_top.qsf, whose relative
# paths start there).  Open build/quartus/de0_cv_top.qpf in the GUI
# afterwards if you like.  `make quartus` does the same through
# python -m torqueloop.flow.quartus, which first checks that the committed .qsf is in
# step with constraints/pins.toml and rtl/manifest.toml.
# The firmware images named in constraints/pins.toml [firmware] must exist
# first: python3 -m torqueloop.flow.boot_image (needs riscv64-unknown-elf-gcc).

set repo [file normalize [file join [file dirname [info script]] ..]]
set proj_dir [file join $repo build quartus]
file mkdir $proj_dir
cd $proj_dir

set qpf [open de0_cv_top.qpf w]
puts $qpf "# Quartus project of the torqueloop board top, written by constraints/create_project.tcl"
puts $qpf "PROJECT_REVISION = \"de0_cv_top\""
close $qpf
file copy -force [file join $repo constraints de0_cv_top.qsf] de0_cv_top.qsf
puts "Info: Quartus project written to $proj_dir/de0_cv_top.qpf"

# quartus_sh passes the script's arguments in quartus(args) (and argv).
if {[info exists quartus(args)]} {
    set script_args $quartus(args)
} else {
    set script_args $argv
}
if {[llength $script_args] > 0 && [lindex $script_args 0] eq "compile"} {
    load_package flow
    project_open -revision de0_cv_top de0_cv_top
    execute_flow -compile
    project_close
    puts "Info: bitstream $proj_dir/output_files/de0_cv_top.sof"
}
