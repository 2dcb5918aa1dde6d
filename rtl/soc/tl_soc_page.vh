// SPDX-License-Identifier: MIT
// The bus side of a peripheral page, written once for every block of the
// SoC (docs/soc.md, Bus): tl_soc_fabric sends each page a request bundle
// (strobe, we, word index, write mask and bits: regmap.vh's TL_BUS_REQ_*)
// and registers the block's combinational answer (read value and "no such
// register": TL_BUS_RSP_*).  Macros, not module items: a port list cannot
// come from anything else.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`ifndef TL_SOC_PAGE_VH
`define TL_SOC_PAGE_VH

// The two ports: the fabric's request to this page, this block's answer
// (combinational; the fabric registers it).  A block that reads only some
// bits of the request wraps the use in verilator lint_off UNUSEDSIGNAL.
`define SOC_PAGE_PORTS \
    input  wire [`TL_BUS_REQ_WIDTH-1:0] bus_req, \
    output wire [`TL_BUS_RSP_WIDTH-1:0] bus_rsp

// The answer: the block's read decode sets rdata and err (in an always @(*)).
`define SOC_PAGE_RSP \
    reg  [31:0] rdata; \
    reg         err; \
    assign bus_rsp = {err, rdata};

// The request's fields, for a block that writes registers: wr (a write to
// this page this cycle), the word index and the write mask and bits (the
// bus has merged the byte enables into them: new = (old & ~wmask) | wbits).
`define SOC_PAGE_WRITE \
    wire        wr    = bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB]; \
    wire [9:0]  idx   = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB]; \
    wire [31:0] wmask = bus_req[`TL_BUS_REQ_WMASK_MSB:`TL_BUS_REQ_WMASK_LSB]; \
    wire [31:0] wbits = bus_req[`TL_BUS_REQ_WBITS_MSB:`TL_BUS_REQ_WBITS_LSB];

`endif
