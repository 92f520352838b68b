// Self-checking testbench of dither_ordered: fields per vector: x, px, py, ox, oy, expected c,
// expected sat. The vectors stream through the handshake (hs_tb.vh).
`timescale 1ns/1ps
`include "params.vh"
module tb_dither_ordered;
    `include "hs_tb.vh"
    reg [63:0] e, es;
    reg [`P_X_BITS-1:0] x;
    reg [`P_LOG_N-1:0] px, py, ox, oy;
    wire [`P_O_BITS-1:0] c;
    wire sat;
    dither_ordered #(.X_BITS(`P_X_BITS), .S(`P_S), .LOG_N(`P_LOG_N), .O_BITS(`P_O_BITS),
                     .OMAX(`P_OMAX), .ROM_FILE("dither_rom.hex"))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
             .out_valid(out_valid), .out_ready(out_ready), .x(x), .px(px), .py(py), .ox(ox),
             .oy(oy), .c(c), .sat(sat));
    task drive(input integer k);
        begin
            x = mem[k*`N_FIELDS];
            px = mem[k*`N_FIELDS+1];
            py = mem[k*`N_FIELDS+2];
            ox = mem[k*`N_FIELDS+3];
            oy = mem[k*`N_FIELDS+4];
        end
    endtask
    task check(input integer k, output reg bad_k);
        begin
            e = mem[k*`N_FIELDS+5];
            es = mem[k*`N_FIELDS+6];
            bad_k = c !== e[`P_O_BITS-1:0] || e >> `P_O_BITS != 0 || sat !== es[0] || es > 1;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (x=%0h px=%0h py=%0h expected c=%0h sat=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1],
                 mem[first*`N_FIELDS+2], mem[first*`N_FIELDS+5], mem[first*`N_FIELDS+6]);
    endtask
endmodule
