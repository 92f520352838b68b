// Self-checking testbench of dither_ordered: fields per vector: x, px, py, ox, oy, expected c, expected sat.
`timescale 1ns/1ps
`include "params.vh"
module tb_dither_ordered;
    reg clk = 0;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [63:0] e, es;
    reg [`P_X_BITS-1:0] x;
    reg [`P_LOG_N-1:0] px, py, ox, oy;
    wire [`P_O_BITS-1:0] c;
    wire sat;
    integer k, errors, first;
    dither_ordered #(.X_BITS(`P_X_BITS), .S(`P_S), .LOG_N(`P_LOG_N), .O_BITS(`P_O_BITS),
                     .OMAX(`P_OMAX), .ROM_FILE("dither_rom.hex"))
        dut (.clk(clk), .x(x), .px(px), .py(py), .ox(ox), .oy(oy), .c(c), .sat(sat));
    initial begin
        $readmemh("vectors.hex", mem);
        errors = 0;
        first = -1;
        for (k = 0; k < `N_VECTORS; k = k + 1) begin
            x = mem[k*`N_FIELDS];
            px = mem[k*`N_FIELDS+1];
            py = mem[k*`N_FIELDS+2];
            ox = mem[k*`N_FIELDS+3];
            oy = mem[k*`N_FIELDS+4];
            #1 clk = 1;
            #1 clk = 0;
            e = mem[k*`N_FIELDS+5];
            es = mem[k*`N_FIELDS+6];
            if (c !== e[`P_O_BITS-1:0] || e >> `P_O_BITS != 0 || sat !== es[0] || es > 1) begin
                if (errors == 0) first = k;
                errors = errors + 1;
            end
        end
        if (errors == 0) $display("TESTBENCH OK %0d vectors", `N_VECTORS);
        else $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (x=%0h px=%0h py=%0h expected c=%0h sat=%0h)",
                      errors, `N_VECTORS, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1],
                      mem[first*`N_FIELDS+2], mem[first*`N_FIELDS+5], mem[first*`N_FIELDS+6]);
        $finish;
    end
endmodule
