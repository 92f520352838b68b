// Self-checking testbench of log_adder: fields per vector: a, b, expected s.
`timescale 1ns/1ps
`include "params.vh"
module tb_log_adder;
    reg clk = 0;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [63:0] e;
    reg [`P_FB-1:0] a, b;
    wire [`P_FB-1:0] s;
    integer k, errors, first;
    log_adder #(.FB(`P_FB), .TD(`P_TD), .TF(`P_TF), .ADDR_BITS(`P_ADDR_BITS), .SHIFT(`P_SHIFT),
                .INTERP(`P_INTERP), .MAX(`P_MAX), .ROM_FILE("log_rom.hex"))
        dut (.clk(clk), .a(a), .b(b), .s(s));
    initial begin
        $readmemh("vectors.hex", mem);
        errors = 0;
        first = -1;
        for (k = 0; k < `N_VECTORS; k = k + 1) begin
            a = mem[k*`N_FIELDS];
            b = mem[k*`N_FIELDS+1];
            #1 clk = 1;
            #1 clk = 0;
            e = mem[k*`N_FIELDS+2];
            if (s !== e[`P_FB-1:0] || e >> `P_FB != 0) begin
                if (errors == 0) first = k;
                errors = errors + 1;
            end
        end
        if (errors == 0) $display("TESTBENCH OK %0d vectors", `N_VECTORS);
        else $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (a=%0h b=%0h expected s=%0h)",
                      errors, `N_VECTORS, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1], mem[first*`N_FIELDS+2]);
        $finish;
    end
endmodule
