// SPDX-License-Identifier: MIT
// tl_soc_pages: the peripheral region's decode, combinational - one request
// bundle per 4 KiB page, and the addressed page's response.
//
// Every page sees the same request fields (docs/soc.md, Bus); only the
// addressed page's strobe is set.  A page marked empty in PAGE_USED answers
// every access with "no such register", whatever its bus_rsp slice carries,
// so its block may be left out.  The caller acknowledges and registers the
// response (tl_soc_fabric in the SoC, tb/cpu/cpu_sim_top in the CPU's test
// harness, which use the same blocks at the same pages).
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`default_nettype none

module tl_soc_pages #(
    parameter integer N_PAGES   = `TL_PERIPH_SIZE / 4096,
    parameter integer PAGE_BITS = $clog2(N_PAGES),
    parameter [N_PAGES-1:0] PAGE_USED = {N_PAGES{1'b1}}   // bit p: page p has a block
) (
    input  wire                   stb,        // an access to the peripheral region starts now
    input  wire                   we,
    input  wire [3:0]             be,
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [PAGE_BITS+11:0]  addr,       // byte offset in the region
    /* verilator lint_on UNUSEDSIGNAL */
    input  wire [31:0]            wdata,
    output wire [N_PAGES*`TL_BUS_REQ_WIDTH-1:0] page_req,   // page p at [p*width +: width]
    /* verilator lint_off UNUSEDSIGNAL */  // an empty page's slice is not read: no block answers there
    input  wire [N_PAGES*`TL_BUS_RSP_WIDTH-1:0] page_rsp,
    /* verilator lint_on UNUSEDSIGNAL */
    output wire [`TL_BUS_RSP_WIDTH-1:0]         rsp         // the addressed page's answer
);

    localparam integer RQ = `TL_BUS_REQ_WIDTH;
    localparam integer RS = `TL_BUS_RSP_WIDTH;
    // The answer of an empty page: no such register.
    localparam [RS-1:0] RSP_NONE = {{(RS - 1){1'b0}}, 1'b1} << `TL_BUS_RSP_ERR_LSB;

    wire [PAGE_BITS-1:0] page  = addr[12 +: PAGE_BITS];
    wire [31:0]          wmask = {{8{be[3]}}, {8{be[2]}}, {8{be[1]}}, {8{be[0]}}};
    wire [N_PAGES*RS-1:0] answer;

    genvar p;
    generate
        for (p = 0; p < N_PAGES; p = p + 1) begin : g_page
            assign page_req[p*RQ + `TL_BUS_REQ_STB_LSB] = stb && page == p;
            assign page_req[p*RQ + `TL_BUS_REQ_WE_LSB]  = we;
            assign page_req[p*RQ + `TL_BUS_REQ_IDX_LSB   +: 10] = addr[11:2];
            assign page_req[p*RQ + `TL_BUS_REQ_WMASK_LSB +: 32] = wmask;
            assign page_req[p*RQ + `TL_BUS_REQ_WBITS_LSB +: 32] = wdata & wmask;
            if (PAGE_USED[p]) begin : g_used
                assign answer[p*RS +: RS] = page_rsp[p*RS +: RS];
            end else begin : g_empty
                assign answer[p*RS +: RS] = RSP_NONE;
            end
        end
    endgenerate

    // The addressed page's answer (a mux over the pages).
    reg [RS-1:0] selected;
    integer k;
    always @(*) begin
        selected = RSP_NONE;
        for (k = 0; k < N_PAGES; k = k + 1)
            if (page == k[PAGE_BITS-1:0])
                selected = answer[k*RS +: RS];
    end
    assign rsp = selected;

endmodule

`default_nettype wire
